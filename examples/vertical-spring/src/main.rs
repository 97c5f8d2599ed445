//! The whole `pendkit` command line with the tutorial's kind linked in (docs/elements.md,
//! "Reaching the tools").

use pendkit_example_vertical_spring as _; // links the kind: it registers itself

fn main() -> std::process::ExitCode {
    pendkit_cli::main()
}
