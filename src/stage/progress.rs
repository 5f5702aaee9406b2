//! How a long stage tells its caller where it is, and how the caller stops it.
//!
//! The caller owns the handle (a progress bar on a terminal, a notebook widget, a Python
//! callback, nothing at all) and hands it to the stage as `&dyn Progress`. The stage calls
//! [`Progress::begin`] at each step, [`Progress::set`] as work is done, and asks
//! [`Progress::cancelled`] between steps: once it is true, the stage returns its error's
//! `Cancelled` variant at the next check, having written nothing (stages write nothing anyway:
//! writers are separate calls).

/// Where a long stage is, and whether its caller wants it stopped. Every method has a default
/// that does nothing, so a handle implements only what it shows.
pub trait Progress: Sync {
    /// A step of the stage begins: its name and how many units of work it has (`None`: not
    /// known, as for a solver's rounds).
    fn begin(&self, _step: &'static str, _total: Option<u64>) {}

    /// `done` units of the current step are finished (from any thread).
    fn set(&self, _done: u64) {}

    /// A line on where the step stands (a solver's deviation after a round).
    fn message(&self, _text: &str) {}

    /// True once the caller wants the stage stopped. Checked between steps: within one brick
    /// of a mesh, one layer of a print, one iteration of a solver, one part of a nest.
    fn cancelled(&self) -> bool {
        false
    }
}

/// The handle that shows nothing and never cancels, for calls that need none.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quiet;

impl Progress for Quiet {}

/// The stage stopped because its caller asked (see [`Progress::cancelled`]); nothing was
/// written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

/// `Err(Cancelled)` once `progress` says stop: the check between two steps.
pub fn checkpoint(progress: &dyn Progress) -> Result<(), Cancelled> {
    if progress.cancelled() {
        Err(Cancelled)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

    struct Counting {
        done: AtomicU64,
        stop: AtomicBool,
    }

    impl Progress for Counting {
        fn set(&self, done: u64) {
            self.done.store(done, Ordering::Relaxed);
            if done >= 3 {
                self.stop.store(true, Ordering::Relaxed);
            }
        }
        fn cancelled(&self) -> bool {
            self.stop.load(Ordering::Relaxed)
        }
    }

    #[test]
    fn a_checkpoint_stops_once_the_handle_says_so() {
        let p = Counting {
            done: AtomicU64::new(0),
            stop: AtomicBool::new(false),
        };
        let mut steps = 0;
        let stopped = (1..=10).try_for_each(|k| {
            checkpoint(&p)?;
            steps += 1;
            p.set(k);
            Ok::<(), Cancelled>(())
        });
        assert_eq!(stopped, Err(Cancelled));
        assert_eq!(steps, 3);
        assert!(checkpoint(&Quiet).is_ok());
    }
}
