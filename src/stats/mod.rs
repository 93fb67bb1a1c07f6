//! Distribution functions computed on the target at configuration time.

mod student_t;

pub use student_t::{
    normal_upper_quantile, student_t_pdf, student_t_upper_quantile, student_t_upper_tail,
    StatsError,
};
