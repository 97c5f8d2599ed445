//! What the command line writes for other programs, one test program: state-space exports
//! (JSON read here; `.npz` read by numpy and `.mat` by scipy, opt-in with
//! PENDKIT_TEST_PYTHON=1) and the HTML report (read here; opened in headless Chromium,
//! opt-in with PENDKIT_TEST_BROWSER=1). `.ci/run` sets both. Each module is one group of
//! tests (a file of its own), with what it checks in its own documentation.

mod report;
mod report_browser;
mod ss_exports;
mod ss_scipy;

/// Whether the opt-in tests gated by the environment variable `var` run: they do when it is
/// `1`. Otherwise this prints one line naming `test`, what it needs and how to enable it, and
/// the caller returns (Rust has no run-time skip: the test passes). The line is written to
/// the process's stderr directly, past the test harness's capture, so `cargo test` shows it.
/// With the variable set, the test runs and a missing tool fails it with its own message.
fn opted_in(var: &str, test: &str, needs: &str) -> bool {
    if std::env::var(var).is_ok_and(|v| v == "1") {
        return true;
    }
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED {test}: needs {needs}; run it with {var}=1"
    );
    false
}
