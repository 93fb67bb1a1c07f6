//! Distribution functions computed on the target at configuration time.

mod chi_square;
mod normal;
mod student_t;

pub use chi_square::{
    chi_square_upper_quantile, chi_square_upper_tail, cusum_run_length, cusum_threshold,
};
pub use normal::normal_upper_quantile;
pub use student_t::{
    student_t_cornish_fisher, student_t_pdf, student_t_upper_quantile, student_t_upper_tail,
    StatsError,
};
