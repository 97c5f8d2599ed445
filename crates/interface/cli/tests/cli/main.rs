//! The command line, one test program: its commands as docs/cli.md specifies them (modes,
//! sensitivity, sweep, fit, tradeoff, suspension files) and what it refuses. Each module is
//! one group of tests (a file of its own), with what it checks in its own documentation.

mod common;

mod cli;
mod elements;
mod fit;
mod limits;
mod modes_accuracy;
mod optical_spring;
mod outputs;
mod refusals;
mod sensitivity;
mod suspension_files;
mod sweep;
mod tradeoff;
