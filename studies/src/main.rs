//! `absorber-studies`: the studies that write docs/ (see `absorber-studies --help`).

fn main() -> std::process::ExitCode {
    host_sim::cli::process(absorber_studies::cli::main)
}
