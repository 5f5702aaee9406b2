//! Progress bars of long commands: on stderr, hidden when it is not a terminal. The bar last
//! made is also kept where the Python package's progress callback can read it.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressDrawTarget};

static ACTIVE: Mutex<Option<(&str, ProgressBar)>> = Mutex::new(None);

/// A new bar for `stage` (a spinner without a length) on stderr, made the one `active` reports.
/// When a command is captured (`say::capture`), nothing is drawn.
pub fn bar(stage: &'static str, len: Option<u64>) -> ProgressBar {
    let target = if super::say::capturing() {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(len, target);
    if let Ok(mut active) = ACTIVE.lock() {
        *active = Some((stage, bar.clone()));
    }
    bar
}

// The binary draws its bars; the Python package reads them (python/src/lib.rs).
/// Where a long command is: the last bar's stage, message, position and length.
#[allow(dead_code)]
pub struct Progress {
    pub stage: &'static str,
    pub message: String,
    pub done: u64,
    pub total: Option<u64>,
}

/// The last bar, while it is not finished.
#[allow(dead_code)]
pub fn active() -> Option<Progress> {
    let active = ACTIVE.lock().ok()?;
    let (stage, bar) = active.as_ref()?;
    (!bar.is_finished()).then(|| Progress {
        stage,
        message: bar.message(),
        done: bar.position(),
        total: bar.length(),
    })
}

/// Forgets the last bar (a new command starts).
#[allow(dead_code)]
pub fn reset() {
    if let Ok(mut active) = ACTIVE.lock() {
        *active = None;
    }
}
