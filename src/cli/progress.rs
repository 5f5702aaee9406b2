//! The command line's progress handle: one bar on stderr for the step a stage is in, hidden
//! when stderr is not a terminal.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar on stderr that follows a stage's steps (`lamina::stage::Progress`).
pub struct Bar {
    bar: ProgressBar,
    /// The current step's name, for the bar's template.
    step: Mutex<&'static str>,
}

impl Bar {
    pub fn new() -> Self {
        Bar {
            bar: ProgressBar::hidden(),
            step: Mutex::new(""),
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

impl lamina::stage::Progress for Bar {
    fn begin(&self, step: &'static str, total: Option<u64>) {
        if let Ok(mut s) = self.step.lock() {
            if *s == step && self.bar.length() == total {
                return;
            }
            *s = step;
        }
        self.bar.finish_and_clear();
        self.bar
            .set_draw_target(indicatif::ProgressDrawTarget::stderr());
        self.bar.reset();
        self.bar.set_length(total.unwrap_or(0));
        let template = match total {
            Some(_) => format!("{step} {{bar:40}} {{pos}}/{{len}} {{msg}} {{elapsed}}"),
            None => format!("{{spinner}} {step}, {{msg}} {{elapsed}}"),
        };
        if let Ok(style) = ProgressStyle::with_template(&template) {
            self.bar.set_style(style);
        }
        if total.is_none() {
            self.bar
                .enable_steady_tick(std::time::Duration::from_millis(120));
        } else {
            self.bar.disable_steady_tick();
        }
    }

    fn set(&self, done: u64) {
        // A stage's total is an estimate (the nester's counts its tries' fills): the bar stops
        // at its end rather than pass 100 %.
        let done = match self.bar.length() {
            Some(len) if len > 0 => done.min(len),
            _ => done,
        };
        self.bar.set_position(done);
    }

    fn message(&self, text: &str) {
        self.bar.set_message(text.to_string());
    }
}

/// A bare bar for `stage` (a spinner without a length) on stderr, for commands that drive
/// their own loops.
pub fn bar(_stage: &'static str, len: Option<u64>) -> ProgressBar {
    ProgressBar::with_draw_target(len, indicatif::ProgressDrawTarget::stderr())
}

#[cfg(test)]
mod tests {
    use super::*;
    use lamina::stage::Progress;

    #[test]
    fn the_bar_stops_at_its_total_when_a_stage_counts_past_its_estimate() {
        let bar = Bar::new();
        bar.begin("nesting", Some(10));
        bar.set(7);
        assert_eq!(bar.bar.position(), 7);
        bar.set(15);
        assert_eq!(bar.bar.position(), 10);
        // A spinner has no total to stop at.
        bar.begin("meshing", None);
        bar.set(15);
        assert_eq!(bar.bar.position(), 15);
    }
}
