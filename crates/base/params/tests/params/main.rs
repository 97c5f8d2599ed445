//! Parameter sets, one test program: resolution, errors and overrides, and the exact
//! tangents. Each module is one group of tests (a file of its own).

mod params;
mod tangent;
