//! What the commands tell the person at the terminal: results on standard output that a
//! closed reader cannot turn into a crash, and progress bars on standard error.
//!
//! * **Standard output.** Every line the commands print goes through [`outln!`](crate::outln) (or
//!   [`out!`](crate::out)): a write that fails (the reader went away, `host-sim … | head`) ends the
//!   printing quietly instead of panicking, the command still writes its files and exits with
//!   its own status, and an error other than a closed pipe is kept for [`stdout_failure`]
//!   (the command line reports it). Messages on standard error go through [`errln!`](crate::errln), which
//!   drops what it cannot write.
//! * **Progress.** [`Progress`] is an `indicatif` bar on standard error, drawn only when
//!   standard error is a terminal: piped or redirected, nothing of it is written.

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Prints a line on standard output, as `println!` does, without panicking when the reader
/// has gone away (see the module docs).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::console::print(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::console::print(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Prints on standard output, as `print!` does, without panicking when the reader has gone
/// away (see the module docs).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::console::print(format_args!($($arg)*))
    };
}

/// Prints a line on standard error, as `eprintln!` does, without panicking when standard error
/// is closed (`2>&1 | head`): a message that cannot be written is dropped.
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::console::print_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes `args` to standard error (the body of [`errln!`](crate::errln)); a failed write is dropped.
pub fn print_err(args: fmt::Arguments<'_>) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// Whether a write to standard output has failed (nothing more is printed).
static CLOSED: AtomicBool = AtomicBool::new(false);

/// The first failure that was not a closed pipe.
static FAILURE: Mutex<Option<String>> = Mutex::new(None);

/// Writes `args` to standard output (the body of [`outln!`](crate::outln) and [`out!`](crate::out)).
pub fn print(args: fmt::Arguments<'_>) {
    if CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut o = io::stdout().lock();
    if let Err(e) = o.write_fmt(args).and_then(|()| o.flush()) {
        CLOSED.store(true, Ordering::Relaxed);
        if e.kind() != io::ErrorKind::BrokenPipe {
            if let Ok(mut f) = FAILURE.lock() {
                f.get_or_insert_with(|| e.to_string());
            }
        }
    }
}

/// The first error writing to standard output other than a closed pipe (a full disk, a
/// revoked terminal), if there was one.
pub fn stdout_failure() -> Option<String> {
    FAILURE.lock().ok().and_then(|f| f.clone())
}

/// A progress bar on standard error, drawn only when standard error is a terminal.
pub struct Progress(ProgressBar);

impl Progress {
    /// A bar of `len` units of work, labelled `what` (the command's name).
    pub fn new(what: &str, len: u64) -> Self {
        Self::to(what, len, ProgressDrawTarget::stderr())
    }

    /// The same, drawn on `target`.
    fn to(what: &str, len: u64, target: ProgressDrawTarget) -> Self {
        let bar = ProgressBar::with_draw_target(Some(len), target);
        if let Ok(style) = ProgressStyle::with_template(
            "{prefix}: [{bar:30}] {pos}/{len} {msg} ({elapsed}, about {eta} left)",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(what.to_string());
        bar.enable_steady_tick(Duration::from_millis(500));
        Self(bar)
    }

    /// Whether the bar is drawn (standard error is a terminal).
    pub fn is_drawn(&self) -> bool {
        !self.0.is_hidden()
    }

    /// One unit done; `msg` says what is being worked on.
    pub fn inc(&self, msg: impl Into<String>) {
        self.0.set_message(msg.into());
        self.0.inc(1);
    }

    /// The bar's message (what is being worked on).
    pub fn message(&self, msg: impl Into<String>) {
        self.0.set_message(msg.into());
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
