//! One module per subcommand. Each `run` returns `Result<(), Failure>`; `main` reports.

pub mod bench;
pub mod bench_error;
pub mod build;
pub mod check;
pub mod demo;
pub mod figures;
pub mod gen;
pub mod inspect;
pub mod locate;
pub mod panels;
pub mod render;
pub mod stability;
pub mod view;

use std::io::Write;
use std::process::ExitCode;

/// Exit status for bad input, unreadable or unwritable files.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit status after a panic (a bug).
pub const EXIT_PANIC: u8 = 101;

/// Why a command failed: the message of the one `error: ` line, and the exit status.
#[derive(Debug)]
pub struct Failure {
    /// The message, without `error: `.
    pub message: String,
    /// The exit status.
    pub code: u8,
}

impl Failure {
    /// A failure caused by bad input (exit status 2).
    pub fn bad_input(message: impl Into<String>) -> Failure {
        Failure {
            message: message.into(),
            code: EXIT_BAD_INPUT,
        }
    }

    /// Prints the one line and gives the exit status.
    pub fn report(&self) -> ExitCode {
        eprintln!("error: {}", one_line(&self.message));
        ExitCode::from(self.code)
    }
}

/// Control characters (newlines included) become spaces: every report is one line.
pub fn one_line(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// Replaces the default panic output (message, backtrace note) with one line and exit
/// status 101. There should be no panics; this is the last resort.
pub fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let _ = writeln!(
            std::io::stderr(),
            "error: internal error (a bug in vcx, please report it): {}",
            panic_message(info)
        );
        std::process::exit(i32::from(EXIT_PANIC));
    }));
}

/// A panic's message and place on one line.
pub fn panic_message(info: &std::panic::PanicHookInfo<'_>) -> String {
    let payload = info.payload();
    let what = payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("unknown cause");
    let place = info
        .location()
        .map(|l| format!(" at {}:{}", l.file(), l.line()))
        .unwrap_or_default();
    one_line(&format!("{what}{place}"))
}

/// Writes `text` to stdout. A closed pipe (`vcx gen … | head`) is not an error.
pub fn write_stdout(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Failure::bad_input(format!("cannot write to stdout: {e}"))),
    }
}
