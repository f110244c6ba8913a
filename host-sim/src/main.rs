//! `host-sim`: the command-line tool (see `host-sim --help`).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
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
    let cli = match host_sim::cli::Cli::try_parse_from(host_sim::cli::with_negative_numbers(
        std::env::args_os(),
    )) {
        Ok(cli) => cli,
        Err(e) => return host_sim::cli::usage_error(e),
    };
    match std::panic::catch_unwind(|| host_sim::cli::main(cli)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("error: {}", format!("{e:#}").replace('\n', " "));
            if e.downcast_ref::<host_sim::output::PointsFailed>().is_some() {
                ExitCode::from(host_sim::output::EXIT_POINTS_FAILED)
            } else {
                ExitCode::FAILURE
            }
        }
        Err(_) => ExitCode::from(101),
    }
}
