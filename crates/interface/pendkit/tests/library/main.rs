//! The library's facade, one test program: the fit against synthetic measurements, and the
//! README's example kept equal to the crate documentation's. Each module is one group of
//! tests (a file of its own).

mod fit;
mod readme;
