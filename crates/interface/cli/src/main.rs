//! The `pendkit` program: the command line of `pendkit_cli` with the shipped element kinds.

fn main() -> std::process::ExitCode {
    pendkit_cli::main()
}
