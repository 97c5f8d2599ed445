//! What pendkit is given, one test program: bad input gives a clear error (never a panic
//! or NaN with success, property tests included), the builder as a downstream tool uses it,
//! case texts, and the bundled model files against the references they were written from.
//! Each module is one group of tests (a file of its own), with what it checks in its own
//! documentation.

mod body_validity;
mod builder;
mod bundled_files;
mod case_text;
mod element_instances;
mod errors;
mod fit_bounds;
mod input_checks;
mod limits;
mod no_silent_nonsense;
mod out_of_range;
mod scenes;
