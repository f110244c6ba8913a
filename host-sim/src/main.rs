//! `host-sim`: the command-line tool (see `host-sim --help`).

fn main() -> std::process::ExitCode {
    absorber_sim::process::process(host_sim::commands::dispatch)
}
