//! `absorber-studies`: the studies that write docs/ (see `absorber-studies --help`).

fn main() -> std::process::ExitCode {
    absorber_sim::process::process(absorber_studies::cli::main)
}
