//! Progress on stderr for work that takes longer than about a second: a bar for counted
//! steps (sweeps, reports), a spinner for one long calculation (modes of a bead model).
//! Nothing is drawn when stderr is not a terminal (pipes, files, tests), nor for work that
//! finishes within the first second.

use std::io::IsTerminal;
use std::sync::mpsc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long work runs before its progress appears.
const DELAY: Duration = Duration::from_secs(1);

/// A progress bar or spinner that shows itself after [`DELAY`], on a terminal only.
pub struct Progress {
    bar: ProgressBar,
    done: Option<mpsc::Sender<()>>,
    watcher: Option<std::thread::JoinHandle<()>>,
}

impl Progress {
    /// A bar of `steps` steps (or a spinner for `None`) with `message` beside it.
    pub fn new(steps: Option<u64>, message: impl Into<String>) -> Progress {
        let bar = match steps {
            Some(n) => ProgressBar::with_draw_target(Some(n), ProgressDrawTarget::hidden())
                .with_style(
                    ProgressStyle::with_template(
                        "{msg} [{bar:30}] {pos}/{len} ({elapsed}, about {eta} left)",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
                ),
            None => ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden()).with_style(
                ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            ),
        };
        bar.set_message(message.into());
        if !std::io::stderr().is_terminal() {
            return Progress {
                bar,
                done: None,
                watcher: None,
            };
        }
        let (done, finished) = mpsc::channel::<()>();
        let shown = bar.clone();
        let watcher = std::thread::spawn(move || {
            if let Err(mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(DELAY) {
                shown.set_draw_target(ProgressDrawTarget::stderr());
                shown.enable_steady_tick(Duration::from_millis(120));
            }
        });
        Progress {
            bar,
            done: Some(done),
            watcher: Some(watcher),
        }
    }

    /// A spinner for one long calculation.
    pub fn spinner(message: impl Into<String>) -> Progress {
        Progress::new(None, message)
    }

    /// One step done.
    pub fn step(&self) {
        self.bar.inc(1);
    }

    /// Changes the message (the step under way).
    pub fn message(&self, message: impl Into<String>) {
        self.bar.set_message(message.into());
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(done) = self.done.take() {
            let _ = done.send(());
        }
        if let Some(watcher) = self.watcher.take() {
            let _ = watcher.join();
        }
        self.bar.finish_and_clear();
    }
}
