//! `host-sim`: the command-line tool (see `host-sim --help`).

fn main() -> std::process::ExitCode {
    host_sim::cli::process(host_sim::commands::dispatch)
}
