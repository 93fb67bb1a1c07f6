//! Running third-party parsers that may panic on corrupt input.
//!
//! [`catch_quietly`] runs a closure under [`std::panic::catch_unwind`] and
//! turns a panic into its message. While it runs, the panic hook prints
//! nothing for panics on the calling thread: the user sees the one-line
//! error the caller builds, not a `thread 'main' panicked at …` report.
//!
//! The hook is swapped once per process for a wrapper that defers to the
//! previous hook unless the panicking thread is inside `catch_quietly`
//! (a thread-local flag). Swapping the hook around each call instead would
//! race with other threads (parallel tests, rayon workers) that panic or
//! swap it themselves.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

fn install_filtering_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

/// Restores the flag even if the closure unwinds.
struct Quiet(bool);

impl Drop for Quiet {
    fn drop(&mut self) {
        QUIET.with(|q| q.set(self.0));
    }
}

/// Runs `f`; a panic inside it becomes `Err(message)` (the panic payload
/// if it is a string) and prints nothing.
pub fn catch_quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install_filtering_hook();
    let _restore = Quiet(QUIET.with(|q| q.replace(true)));
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_its_message_and_the_flag_is_restored() {
        let r: Result<(), String> = catch_quietly(|| {
            let v: Vec<u8> = Vec::new();
            let i = v.len() + 3;
            let _ = v[..i].len();
        });
        let e = r.unwrap_err();
        assert!(e.contains("out of range"), "{e}");
        assert!(!QUIET.with(Cell::get));
        assert_eq!(catch_quietly(|| 7), Ok(7));
    }
}
