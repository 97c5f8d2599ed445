//! What the command line writes for other programs, one test program: state-space exports
//! (JSON read here; `.npz` read by numpy and `.mat` by scipy, opt-in with
//! PENDKIT_TEST_PYTHON=1) and the HTML report (read here; opened in headless Chromium,
//! opt-in with PENDKIT_TEST_BROWSER=1). `.ci/run` sets both. Each module is one group of
//! tests (a file of its own), with what it checks in its own documentation.

mod report;
mod report_browser;
mod ss_exports;
mod ss_scipy;
