//! # uvflat-core
//!
//! Pure-Rust UV parameterization: polygon soup in, per-corner UVs out.
//!
//! Data flow of one unwrap ([`unwrap`]):
//! 1. [`mesh::PolyMesh`] validates the polygon soup (typed [`UvError`] naming the element).
//! 2. [`charts`] splits the selected faces into charts along seams, non-manifold edges,
//!    inconsistently oriented edges and the selection border, triangulates n-gons (as the
//!    render triangulation given in [`MeshInput::triangles`] says, else by ear clipping),
//!    finds boundary loops and classifies each chart.
//! 3. [`methods`] maps every chart (in parallel) with the chosen [`Method`].
//! 4. [`metrics`] measures every chart independently of the solver (flips, a quad counting as
//!    folded when either of its diagonal splits has a flipped triangle; boundary
//!    self-overlap, distortion) and the result carries one [`ChartReport`] per chart.
//!
//! See `ARCHITECTURE.md` at the repository root for the module graph.

pub mod charts;
pub mod cuts;
pub mod error;
mod factor_timing;
pub mod geometry;
pub mod mesh;
pub mod methods;
pub mod metrics;
pub mod progress;
pub mod solvers;
mod schedule;
pub mod pipeline;
mod unwrap;
pub mod validate;

pub use cuts::{auto_seam_options, AutoSeamOptions, Symmetry, UnknownSymmetry};
pub use error::{Result, UvError};
pub use factor_timing::factorization_seconds;
pub use methods::{method_names, BoundaryShape, Method, OptionValue, SpectralOptions};
pub use metrics::{Distortion, MeshMetrics};
pub use progress::Progress;
pub use validate::validate_input;
pub use unwrap::{plan_seams, unwrap, ChartKind, ChartReport, ChartStatus, Fit, MeshInput, Phases, Problem, UnwrapOptions, Unwrapped};
