//! Shared solver pieces: the quadratic-with-fixed-values solver behind every linear method
//! (and the global steps of the iterative ones).

pub mod conjugate_gradient;
pub mod line_search;
pub mod ordering;
mod quadratic;
pub mod refined_llt;

pub use quadratic::{FixedValueSolver, Scalar, Symmetry, DENSE_MAX};
#[cfg(test)]
pub(crate) use quadratic::FORCE_SPARSE;

/// Why a linear solve failed. Turned into a chart failure reason by the methods.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// Cholesky met a non-positive pivot: the system is singular (for example a chart whose
    /// free vertices are not connected to any fixed value).
    #[error("the linear system is not positive definite (disconnected or degenerate chart)")]
    NotPositiveDefinite,
    /// LU found the matrix singular.
    #[error("the linear system is singular")]
    Singular,
    /// The solution contains NaN or infinity.
    #[error("the solve produced non-finite values")]
    NonFinite,
    /// Allocation or another non-numerical failure inside the sparse solver.
    #[error("sparse solver failure: {0}")]
    Other(String),
}
