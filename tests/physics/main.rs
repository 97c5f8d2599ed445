//! Physics against independent references, one test program: closed-form oracles for every
//! stage, the bundled suspensions (quad, triple, chain, violin beads, quad-aligo's own
//! switches), the equilibrium search, block-wise and shift-invert modes, stability verdicts
//! and the link-time registry of element kinds. Each module is one group of tests (a file of
//! its own), with what it checks and its tolerances in its own documentation.

mod beads;
mod chain;
mod continuum_fibre;
mod equilibrium;
mod modes_blocks;
mod neutral;
mod optical_spring;
mod oracles_responses;
mod oracles_stage0a;
mod oracles_wires;
mod point_spring_file;
mod quad;
mod quad_aligo;
mod registry;
mod scenes;
mod stability;
mod triple;
mod violin_modes;
