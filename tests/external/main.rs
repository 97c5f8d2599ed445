//! Comparisons with other programs that are not part of a fresh clone, one test program:
//! pygwinc (installed from PyPI into target/venv-gwinc, so it needs the network once). Opt-in:
//! the tests run with PENDKIT_TEST_NETWORK=1 (.ci/run sets it); otherwise each says it was
//! skipped, and passes.

mod pygwinc_quad_aligo;
