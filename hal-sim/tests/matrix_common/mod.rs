//! What both recovery matrices (`recovery_matrix.rs`, single IMU, and
//! `recovery_matrix_parity.rs`, redundant arrays) share: seeds, the
//! settling and verdict windows of issue 16, and the printed table row.

/// Seeds per cell.
pub const SEEDS: u64 = 3;
/// Valid input before the verdict, s (issue 16).
pub const SETTLE_S: f64 = 10.0;
/// Verdict window after it, s.
pub const CHECK_S: f64 = 5.0;

/// A run's verdict: nominal, or when (s after the last bad sample) and why
/// it was first off nominal in the verdict window.
pub type Outcome = Result<(), (f64, &'static str)>;

/// Prints one table row (runs back to nominal, the first failure) and
/// returns how many runs failed.
pub fn row(name: &str, outcomes: &[Outcome]) -> usize {
    let ok = outcomes.iter().filter(|o| o.is_ok()).count();
    let first = outcomes.iter().find_map(|o| o.err());
    println!(
        "| {name:<34} | {ok}/{} | {} |",
        outcomes.len(),
        first.map_or(String::from("—"), |(t, w)| format!("{w} at +{t:.1} s")),
    );
    outcomes.len() - ok
}

/// Prints a cell's row, marked open when `open` gives why it does not
/// recover yet, and returns the failed runs to count: none for an open
/// cell, which must still fail at least one run (so the list of open cells
/// cannot go stale).
pub fn counted_row(name: &str, outcomes: &[Outcome], open: Option<&str>) -> usize {
    let f = row(
        &format!("{name}{}", if open.is_some() { " (open)" } else { "" }),
        outcomes,
    );
    match open {
        Some(why) => {
            println!("  open: {why}");
            assert!(f > 0, "{name} recovers now: remove it from the open cells");
            0
        }
        None => f,
    }
}
