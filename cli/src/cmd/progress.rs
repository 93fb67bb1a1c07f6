//! Progress on stderr for the commands that can take more than a couple of
//! seconds. `indicatif` draws nothing when stderr is not a terminal, so
//! pipes, `--json` consumers and tests see no progress output; on a
//! terminal, lines printed with `out!` while a spinner runs are printed
//! above it ([`suspend`]) instead of through it.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// The spinner shown now, if any.
static ACTIVE: Mutex<Option<ProgressBar>> = Mutex::new(None);

/// A spinner with a message, ticking on its own until dropped.
pub(crate) struct Spinner(ProgressBar);

impl Spinner {
    /// Replaces the message.
    pub(crate) fn set_message(&self, msg: String) {
        self.0.set_message(msg);
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.0.finish_and_clear();
        if let Ok(mut a) = ACTIVE.lock() {
            *a = None;
        }
    }
}

/// Starts a spinner saying `what`.
pub(crate) fn spinner(what: &str) -> Spinner {
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed} {msg}") {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    if let Ok(mut a) = ACTIVE.lock() {
        *a = Some(bar.clone());
    }
    Spinner(bar)
}

/// Runs `f` (which prints) with the spinner, if any, hidden meanwhile.
pub(crate) fn suspend<R>(f: impl FnOnce() -> R) -> R {
    let bar = ACTIVE.lock().ok().and_then(|a| a.clone());
    match bar {
        Some(b) => b.suspend(f),
        None => f(),
    }
}
