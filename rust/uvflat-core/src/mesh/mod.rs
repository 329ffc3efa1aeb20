//! Topology only: a validated polygon soup with face offsets.
//!
//! Ids are `u32`. Nothing here looks at positions beyond checking they are finite.

use crate::error::{Result, UvError};

/// A validated polygon mesh: positions, flat corner→vertex array and face offsets.
///
/// Invariants (checked by [`PolyMesh::new`], re-checked by [`PolyMesh::sanity_check`]):
/// every face has ≥ 3 corners, no face repeats a vertex, every vertex index is in range,
/// every coordinate is finite.
#[derive(Debug, Clone)]
pub struct PolyMesh<'a> {
    positions: &'a [[f64; 3]],
    corner_verts: &'a [u32],
    face_offsets: Vec<u32>,
}

impl<'a> PolyMesh<'a> {
    /// Validate and wrap a polygon soup.
    ///
    /// Errors: [`UvError::Shape`] when face sizes do not sum to the corner count,
    /// [`UvError::FaceTooSmall`], [`UvError::VertexIndex`], [`UvError::RepeatedVertex`],
    /// [`UvError::NonFinitePosition`].
    pub fn new(positions: &'a [[f64; 3]], corner_verts: &'a [u32], face_sizes: &[u32]) -> Result<Self> {
        for (v, p) in positions.iter().enumerate() {
            if let Some(&x) = p.iter().find(|x| !x.is_finite()) {
                return Err(UvError::NonFinitePosition { vertex: v, value: x });
            }
        }
        let mut face_offsets = Vec::with_capacity(face_sizes.len() + 1);
        face_offsets.push(0u32);
        let mut total: u64 = 0;
        for (f, &s) in face_sizes.iter().enumerate() {
            if s < 3 {
                return Err(UvError::FaceTooSmall { face: f, size: s as u64 });
            }
            total += s as u64;
            if total > corner_verts.len() as u64 {
                return Err(UvError::Shape {
                    what: "face_sizes",
                    detail: format!("face {f} ends at corner {total}, but there are only {} corners", corner_verts.len()),
                });
            }
            face_offsets.push(total as u32);
        }
        if total != corner_verts.len() as u64 {
            return Err(UvError::Shape {
                what: "face_sizes",
                detail: format!("face sizes sum to {total}, but there are {} corners", corner_verts.len()),
            });
        }
        let n_vertices = positions.len();
        let mut last_seen = vec![u32::MAX; n_vertices];
        for f in 0..face_sizes.len() {
            let (a, b) = (face_offsets[f] as usize, face_offsets[f + 1] as usize);
            for c in a..b {
                let v = corner_verts[c] as usize;
                if v >= n_vertices {
                    return Err(UvError::VertexIndex { face: f, corner: c, vertex: v as u64, n_vertices });
                }
                if last_seen[v] == f as u32 {
                    return Err(UvError::RepeatedVertex { face: f, vertex: v });
                }
                last_seen[v] = f as u32;
            }
        }
        Ok(Self { positions, corner_verts, face_offsets })
    }

    /// Check that every seam names existing vertices.
    pub fn validate_seams(&self, seams: &[[u32; 2]]) -> Result<()> {
        let n_vertices = self.positions.len();
        for (i, s) in seams.iter().enumerate() {
            for &v in s {
                if v as usize >= n_vertices {
                    return Err(UvError::SeamIndex { seam: i, vertex: v as u64, n_vertices });
                }
            }
        }
        Ok(())
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.face_offsets.len() - 1
    }
    /// Number of corners.
    pub fn n_corners(&self) -> usize {
        self.corner_verts.len()
    }
    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.positions.len()
    }
    /// Vertex positions.
    pub fn positions(&self) -> &'a [[f64; 3]] {
        self.positions
    }
    /// Corner range of face `f`.
    pub fn face_corners(&self, f: usize) -> std::ops::Range<usize> {
        self.face_offsets[f] as usize..self.face_offsets[f + 1] as usize
    }
    /// Vertex of corner `c`.
    pub fn corner_vert(&self, c: usize) -> u32 {
        self.corner_verts[c]
    }
    /// The corner after `c` in its face (cyclically), given the face `f` of `c`.
    pub fn next_corner(&self, f: usize, c: usize) -> usize {
        let r = self.face_corners(f);
        if c + 1 == r.end {
            r.start
        } else {
            c + 1
        }
    }

    /// Re-check the invariants; used by tests.
    pub fn sanity_check(&self) {
        assert_eq!(*self.face_offsets.last().unwrap() as usize, self.corner_verts.len());
        for f in 0..self.n_faces() {
            let r = self.face_corners(f);
            assert!(r.len() >= 3, "face {f} too small");
            for c in r.clone() {
                assert!((self.corner_verts[c] as usize) < self.positions.len());
            }
        }
    }
}
