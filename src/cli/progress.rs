//! Progress bars of long commands: on stderr, hidden when it is not a terminal. The bar a
//! thread made last is also kept where the Python package's progress callback can read it
//! (each thread its own, so commands run from several Python threads at once do not mix).

use std::sync::Mutex;
use std::thread::ThreadId;

use indicatif::{ProgressBar, ProgressDrawTarget};

type Active = (ThreadId, &'static str, ProgressBar);

static ACTIVE: Mutex<Vec<Active>> = Mutex::new(Vec::new());

/// A new bar for `stage` (a spinner without a length) on stderr, made the one `active` reports
/// for this thread. When a command is captured (`say::capture`), nothing is drawn.
pub fn bar(stage: &'static str, len: Option<u64>) -> ProgressBar {
    let target = if super::say::capturing() {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(len, target);
    let me = std::thread::current().id();
    if let Ok(mut active) = ACTIVE.lock() {
        active.retain(|(t, ..)| *t != me);
        active.push((me, stage, bar.clone()));
    }
    bar
}

/// Where a long command is: the last bar's stage, message, position and length.
#[allow(dead_code)]
pub struct Progress {
    pub stage: &'static str,
    pub message: String,
    pub done: u64,
    pub total: Option<u64>,
}

/// The last bar `thread` made, while it is not finished.
#[allow(dead_code)]
pub fn active(thread: ThreadId) -> Option<Progress> {
    let active = ACTIVE.lock().ok()?;
    let (_, stage, bar) = active.iter().find(|(t, ..)| *t == thread)?;
    (!bar.is_finished()).then(|| Progress {
        stage,
        message: bar.message(),
        done: bar.position(),
        total: bar.length(),
    })
}

/// Forgets this thread's last bar (a command starts or ends).
#[allow(dead_code)]
pub fn reset() {
    let me = std::thread::current().id();
    if let Ok(mut active) = ACTIVE.lock() {
        active.retain(|(t, ..)| *t != me);
    }
}
