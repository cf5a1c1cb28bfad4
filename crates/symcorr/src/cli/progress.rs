//! Progress display: indicatif bars and spinners on a terminal (stderr), nothing when piped.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::Duration;

fn visible() -> bool {
    std::io::stderr().is_terminal()
}

/// A spinner with a message, hidden unless stderr is a terminal.
pub struct Spinner(Option<ProgressBar>);

impl Spinner {
    /// Starts a spinner showing `message`.
    pub fn new(message: &str) -> Spinner {
        if !visible() {
            return Spinner(None);
        }
        let pb = ProgressBar::new_spinner();
        pb.set_message(message.to_string());
        pb.enable_steady_tick(Duration::from_millis(120));
        Spinner(Some(pb))
    }

    /// Changes the message.
    pub fn set(&self, message: &str) {
        if let Some(pb) = &self.0 {
            pb.set_message(message.to_string());
        }
    }

    /// Removes the spinner.
    pub fn finish(&self) {
        if let Some(pb) = &self.0 {
            pb.finish_and_clear();
        }
    }
}

/// A counting bar, hidden unless stderr is a terminal.
pub struct Bar(Option<ProgressBar>);

impl Bar {
    /// A hidden-or-visible bar.
    pub fn new() -> Bar {
        if !visible() {
            return Bar(None);
        }
        let pb = ProgressBar::new(0);
        if let Ok(style) = ProgressStyle::with_template("{msg:18} [{bar:30}] {pos}/{len} {elapsed}")
        {
            pb.set_style(style.progress_chars("=> "));
        }
        Bar(Some(pb))
    }

    /// A bar for a stream of frames: rate and time left.
    pub fn frames() -> Bar {
        if !visible() {
            return Bar(None);
        }
        let pb = ProgressBar::new(0);
        if let Ok(style) = ProgressStyle::with_template(
            "{msg:10} [{bar:30}] {pos}/{len} frames {per_sec} eta {eta}",
        ) {
            pb.set_style(style.progress_chars("=> "));
        }
        Bar(Some(pb))
    }

    /// Shows `done` of `total` under `message`.
    pub fn update(&self, message: &'static str, done: usize, total: usize) {
        if let Some(pb) = &self.0 {
            pb.set_message(message);
            pb.set_length(total as u64);
            pb.set_position(done as u64);
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(pb) = &self.0 {
            pb.finish_and_clear();
        }
    }
}
