//! Running a stage from Python: on a worker thread with the GIL released, inside this process's
//! own thread pool (made afresh in a forked child), while the calling thread watches for Ctrl-C
//! and calls the progress callback; either stops the stage at its next check.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

use pyo3::prelude::*;

/// How often the calling thread looks for Ctrl-C.
const WATCH_EVERY: Duration = Duration::from_millis(20);
/// How often the progress callback is called.
const PROGRESS_EVERY: Duration = Duration::from_millis(100);

/// The thread pool of this process: rayon's global pool would be inherited by a forked child
/// without its threads (and block it forever), so each process makes its own on first use.
fn pool() -> PyResult<Arc<rayon::ThreadPool>> {
    static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((owner, p)) = slot.as_ref() {
        if *owner == pid {
            return Ok(p.clone());
        }
    }
    // A parent's pool (after a fork): its threads are not here; leave it untouched.
    if let Some(old) = slot.take() {
        std::mem::forget(old);
    }
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|k| format!("lamina-{k}"))
            .build()
            .map_err(|e| crate::error(format!("cannot start the thread pool: {e}")))?,
    );
    *slot = Some((pid, p.clone()));
    Ok(p)
}

/// The stage's view of its caller: where it is, and whether to stop.
pub struct Handle {
    stop: AtomicBool,
    done: AtomicU64,
    state: Mutex<(&'static str, Option<u64>, String)>,
}

impl Handle {
    fn new() -> Self {
        Handle {
            stop: AtomicBool::new(false),
            done: AtomicU64::new(0),
            state: Mutex::new(("", None, String::new())),
        }
    }

    fn snapshot(&self) -> (&'static str, String, u64, Option<u64>) {
        let s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        // A stage's total is an estimate (the nester's counts its tries' fills): `done` never
        // passes it, as the command line's bar stops at its end (a total of 0 is none).
        let done = self.done.load(Ordering::Relaxed);
        let most = s.1.filter(|&t| t > 0).unwrap_or(u64::MAX);
        (s.0, s.2.clone(), done.min(most), s.1)
    }
}

impl lamina::stage::Progress for Handle {
    fn begin(&self, step: &'static str, total: Option<u64>) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        *s = (step, total, String::new());
        self.done.store(0, Ordering::Relaxed);
    }

    fn set(&self, done: u64) {
        self.done.store(done, Ordering::Relaxed);
    }

    fn message(&self, text: &str) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.2 = text.to_string();
    }

    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Runs `work` (a stage) with the GIL released, on a worker in this process's pool. The calling
/// thread checks for Ctrl-C every 20 ms and calls `progress(stage, message, done, total)` about
/// ten times a second; a signal's exception, an exception from the callback, or the callback
/// returning False stops the stage at its next check and is raised here (False raises
/// `lamina.Cancelled`). Errors of the stage become `LaminaError`.
pub fn run<T, E>(
    py: Python<'_>,
    progress: Option<&Py<PyAny>>,
    work: impl FnOnce(&Handle) -> Result<T, E> + Send,
) -> PyResult<T>
where
    T: Send,
    E: std::fmt::Display + Send,
{
    if let Some(p) = progress {
        if !p.bind(py).is_callable() {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "progress= must be callable as progress(stage, message, done, total)",
            ));
        }
    }
    let pool = pool()?;
    let handle = Handle::new();
    let mut raised: Option<PyErr> = None;
    let result = std::thread::scope(|scope| {
        let (finished, wait) = mpsc::sync_channel::<()>(1);
        // A Mutex makes the receiver shareable with the thread that waits on it unlocked.
        let wait = Mutex::new(wait);
        let h = &handle;
        let pool = &pool;
        let worker = scope.spawn(move || {
            let out = pool.install(|| work(h));
            drop(finished);
            out
        });
        let mut last = Instant::now();
        loop {
            let gone = py.detach(|| {
                let wait = wait.lock().unwrap_or_else(|e| e.into_inner());
                matches!(
                    wait.recv_timeout(WATCH_EVERY),
                    Err(mpsc::RecvTimeoutError::Disconnected) | Ok(())
                )
            });
            if gone {
                break;
            }
            if raised.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                raised = Some(e);
                handle.stop.store(true, Ordering::Relaxed);
                continue;
            }
            if let Some(cb) = progress {
                if last.elapsed() >= PROGRESS_EVERY {
                    last = Instant::now();
                    let (stage, message, done, total) = handle.snapshot();
                    if !stage.is_empty() {
                        match cb.call1(py, (stage, message, done, total)) {
                            Err(e) => {
                                raised = Some(e);
                                handle.stop.store(true, Ordering::Relaxed);
                            }
                            Ok(r) if r.bind(py).is(pyo3::types::PyBool::new(py, false)) => {
                                raised =
                                    Some(crate::cancelled("the progress callback returned False"));
                                handle.stop.store(true, Ordering::Relaxed);
                            }
                            Ok(_) => {}
                        }
                    }
                }
            }
        }
        py.detach(|| worker.join())
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match result {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(crate::error(e.to_string())),
        Err(_) => Err(crate::error(
            "internal error: the stage panicked (this is a bug, please report it)".into(),
        )),
    }
}

/// Runs `background` (short Rust work that needs no Python) on this process's pool while the
/// calling thread, holding the GIL, does `foreground` (turning results into Python objects);
/// returns both once both are done. The wait for `background` releases the GIL.
pub fn beside<'py, A, B>(
    py: Python<'py>,
    background: impl FnOnce() -> A + Send,
    foreground: impl FnOnce() -> PyResult<B>,
) -> PyResult<(A, B)>
where
    A: Send,
{
    let pool = pool()?;
    let (a, b) = std::thread::scope(|scope| {
        let pool = &pool;
        let worker = scope.spawn(move || pool.install(background));
        let b = foreground();
        (py.detach(|| worker.join()), b)
    });
    let a = a.map_err(|_| {
        crate::error("internal error: a stage panicked (this is a bug, please report it)".into())
    })?;
    Ok((a, b?))
}
