//! Progress on stderr for the commands that can take more than a couple of
//! seconds. `indicatif` draws nothing when stderr is not a terminal, so
//! pipes and tests see no progress output.

use indicatif::{ProgressBar, ProgressStyle};

/// A spinner with a message, ticking on its own.
pub(crate) fn spinner(what: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed} {msg}") {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}
