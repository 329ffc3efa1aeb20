//! One validation of everything an entry point reads from the user, before any work is done.
//!
//! [`crate::unwrap`], [`crate::metrics::measure`] and [`crate::factorization_seconds`] all call
//! [`validate_input`], so the same input is accepted or refused the same way everywhere and no
//! later stage can index out of range.

use crate::error::{Result, UvError};
use crate::mesh::PolyMesh;
use crate::methods::{abf, Method};
use crate::unwrap::{Fit, MeshInput};

/// Validate a mesh input, and optionally the placement and the method that go with it.
///
/// Checks, in order:
/// * the polygon soup ([`PolyMesh::new`]: finite positions, face sizes ≥ 3 summing to the
///   corner count, vertex indices in range, no vertex repeated in a face);
/// * seams name existing vertices;
/// * `selected` has one entry per face;
/// * pins name existing corners and carry finite UVs;
/// * [`Fit::Previous`] has one UV per corner, finite on every corner of a selected face (the
///   corners of unselected faces are never read, so they may hold anything, NaN included);
/// * the method's options are in range ([`Method::validate`]) and ABF's prescribed angle sums
///   name vertices used by a face, with a sum below 2π times the vertex's corner count.
///
/// Errors: the [`UvError`] variant naming the first offending element.
pub fn validate_input<'a>(input: &MeshInput<'a>, fit: Option<&Fit>, method: Option<&Method>) -> Result<PolyMesh<'a>> {
    let mesh = PolyMesh::new(input.positions, input.corner_verts, input.face_sizes)?;
    let n_corners = mesh.n_corners();
    mesh.validate_seams(input.seams)?;
    if let Some(sel) = input.selected {
        if sel.len() != mesh.n_faces() {
            return Err(UvError::Shape {
                what: "selected",
                detail: format!("has {} entries, mesh has {} faces", sel.len(), mesh.n_faces()),
            });
        }
    }
    for (i, &(c, uv)) in input.pins.iter().enumerate() {
        if c as usize >= n_corners {
            return Err(UvError::PinIndex { pin: i, corner: c as u64, n_corners });
        }
        if !uv[0].is_finite() || !uv[1].is_finite() {
            return Err(UvError::NonFinitePin { pin: i, corner: c as usize });
        }
    }
    if let Some(Fit::Previous(prev)) = fit {
        if prev.len() != n_corners {
            return Err(UvError::Shape {
                what: "fit_to",
                detail: format!("has {} UVs, mesh has {} corners", prev.len(), n_corners),
            });
        }
        for f in 0..mesh.n_faces() {
            if input.selected.is_some_and(|s| !s[f]) {
                continue;
            }
            if let Some(c) = mesh.face_corners(f).find(|&c| !prev[c][0].is_finite() || !prev[c][1].is_finite()) {
                return Err(UvError::NonFiniteUv { corner: c });
            }
        }
    }
    if let Some(method) = method {
        method.validate()?;
        if let Method::Abf(o) = method {
            if !o.angle_sums.is_empty() {
                let mut corners = vec![0u32; input.positions.len()];
                for &v in input.corner_verts {
                    corners[v as usize] += 1;
                }
                if corners.is_empty() {
                    let (v, t) = o.angle_sums[0];
                    return Err(UvError::AngleSum {
                        entry: 0,
                        vertex: v as u64,
                        value: t,
                        reason: "vertex index out of range (mesh has 0 vertices)".into(),
                    });
                }
                abf::validate_angle_sums(&o.angle_sums, &corners)?;
            }
        }
    }
    Ok(mesh)
}
