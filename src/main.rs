//! The `mbsa` command-line tool: a thin layer over the `mbsa` library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
