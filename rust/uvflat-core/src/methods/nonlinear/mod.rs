//! The shared kernel of the nonlinear methods (ARAP, SLIM, MIPS, scaffold; ABF uses the
//! iteration report only through its own Newton loop).
//!
//! One concept per file:
//!
//! * [`jacobian`]: per-triangle rest shapes and the linear map from a triangle's UVs to its
//!   Jacobian ([`TriangleOperators`]), one type for every method;
//! * [`energy`]: the distortion densities (symmetric Dirichlet, MIPS, ARAP), their
//!   area-weighted chart energies, and the energy-optimal uniform scale;
//! * [`hessian`]: the densities' gradients and Hessians by the Jacobian, projected onto the
//!   positive semidefinite cone for Newton steps (MIPS, SLIM);
//! * [`proxy`]: the local steps: closest rotation (ARAP) and SLIM's reweighted proxy;
//! * [`start`]: flip-free starting maps (LSCM, mean value on a circle) and the choice among them;
//! * [`pins`]: how methods whose energy ignores pins honour them (anchors of a global step, a
//!   least-squares similarity after the solve, a similarity gauge);
//! * [`pattern`]: the sparsity pattern of the 2×2-block systems over interleaved (u, v)
//!   unknowns (triplets for [`crate::solvers::FixedValueSolver`], or a CSC pattern with slots);
//! * [`iterate`]: the iteration bookkeeping: energy history, relative-change tolerance,
//!   cancellation, and the report's notes.

pub mod energy;
pub mod hessian;
pub mod iterate;
pub mod jacobian;
pub mod pattern;
pub mod pins;
pub mod proxy;
pub mod start;
pub mod unfold;

pub use jacobian::{Jacobian, TriangleOperators};
