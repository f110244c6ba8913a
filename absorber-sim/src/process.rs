//! A command-line tool of this workspace as a process (`host-sim`, and the studies' developer
//! tool `absorber-studies`): its arguments parsed (negative numbers as values), its outcome as
//! the exit code, a panic reported on one line.

use anyhow::Result;
use clap::Parser;

/// The command line with every `--option <negative number>` written `--option=<negative
/// number>`, so that a negative value in any notation reaches the option's own check (which
/// names the allowed range): clap takes `-1e-3` or `-1,4` for a short flag otherwise and reports
/// an "unexpected argument".
pub fn with_negative_numbers(
    args: impl IntoIterator<Item = std::ffi::OsString>,
) -> Vec<std::ffi::OsString> {
    let negative = |a: &str| {
        let rest = a.strip_prefix('-').unwrap_or("");
        rest.starts_with(|c: char| c.is_ascii_digit() || c == '.')
            && rest
                .chars()
                .all(|c| c.is_ascii_digit() || ".eE+-,".contains(c))
            || ["inf", "infinity", "nan"].contains(&rest.to_ascii_lowercase().as_str())
    };
    let mut out: Vec<std::ffi::OsString> = Vec::new();
    for a in args {
        let joined = match (out.last().and_then(|p| p.to_str()), a.to_str()) {
            (Some(prev), Some(v))
                if prev.starts_with("--")
                    && !prev.contains('=')
                    && prev.len() > 2
                    && negative(v) =>
            {
                Some(format!("{prev}={v}"))
            }
            _ => None,
        };
        match joined {
            Some(j) => {
                out.pop();
                out.push(j.into());
            }
            None => out.push(a),
        }
    }
    out
}

/// A command-line tool of this workspace as a process (`host-sim`, and the studies' developer
/// tool): parses the arguments of `C` (negative numbers as values), runs `run` and turns its
/// outcome into the exit code its help documents: 0 success; 1 error (one line on stderr);
/// 2 usage error; 3 completed with failed points ([`PointsFailed`](crate::output::PointsFailed));
/// 101 a panic (a bug, reported on one line).
pub fn process<C: Parser>(run: impl FnOnce(C) -> Result<()>) -> std::process::ExitCode {
    use std::process::ExitCode;
    // A file-size limit (`ulimit -f`) kills a process with SIGXFSZ by default, with no word;
    // ignored, the write fails with EFBIG and the output layer names the file and keeps the
    // previous result, as for a full disk.
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to SIG_IGN at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    // Safety net: a panic would be a bug; report it on one line, without a backtrace.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("error: internal error (panic{at}): {msg}");
    }));
    let cli = match C::try_parse_from(with_negative_numbers(std::env::args_os())) {
        Ok(cli) => cli,
        Err(e) => return usage_error::<C>(e),
    };
    // The process ends after a panic: nothing observes state it may have left half-updated.
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli))) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("error: {}", format!("{e:#}").replace('\n', " "));
            if e.downcast_ref::<crate::output::PointsFailed>().is_some() {
                ExitCode::from(crate::output::EXIT_POINTS_FAILED)
            } else {
                ExitCode::FAILURE
            }
        }
        Err(_) => ExitCode::from(101),
    }
}

/// Reports a command line clap refused and returns its exit code (2; 0 for `--help` and
/// `--version`). An unknown command is named with the commands there are.
pub fn usage_error<C: clap::CommandFactory>(e: clap::Error) -> std::process::ExitCode {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if e.kind() == ErrorKind::InvalidSubcommand {
        let given = match e.get(ContextKind::InvalidSubcommand) {
            Some(ContextValue::String(s)) => s.clone(),
            _ => String::new(),
        };
        let command = C::command();
        let commands: Vec<String> = command
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect();
        eprintln!(
            "error: unknown command `{given}` (allowed: {}; `{} --help` says what each does)",
            commands.join(", "),
            command.get_name()
        );
        return std::process::ExitCode::from(2);
    }
    let code = e.exit_code();
    // clap prints help and errors itself (with colour on a terminal).
    let _ = e.print();
    std::process::ExitCode::from(u8::try_from(code).unwrap_or(2))
}
