//! The library's facade, one test program: the fit against synthetic measurements, the
//! README's example kept equal to the crate documentation's, and the crates' layering as
//! docs/architecture.md states it. Each module is one group of tests (a file of its own).

mod fit;
mod layers;
mod readme;
