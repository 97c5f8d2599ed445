//! Derivatives and fast paths against independent references, one test program: the
//! sensitivities, a stage's exact tangent, the model generic over the scalar, and the fast
//! derivative, response and stage-matrix paths against their straightforward references.
//! Each module is one group of tests (a file of its own), with what it checks and its
//! tolerances in its own documentation.

mod dual_model;
mod fast_derivatives;
mod fast_responses;
mod sensitivity;
mod stage_model;
mod stage_tangent;
