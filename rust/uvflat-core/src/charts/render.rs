//! The render triangulation of a polygon mesh: the triangles Blender draws, bakes and exports
//! (`mesh.loop_triangles`), given as triples of corner indices.
//!
//! Engines and exporters split n-gons along their own diagonals; a UV map that is flip-free on
//! the core's own split can fold on theirs. Given the render triangulation, charts use it for
//! faces of four or more corners, so that what the methods keep positive and what the metrics
//! count is what the user sees.

use crate::error::{Result, UvError};
use crate::mesh::PolyMesh;

/// A validated render triangulation: for every face, `corners − 2` triangles over the face's
/// own corner positions (0-based within the face), each listed in the face's winding order.
#[derive(Debug, Clone)]
pub struct FaceTriangulation {
    offsets: Vec<u32>,
    triangles: Vec<[u32; 3]>,
}

impl FaceTriangulation {
    /// Validate `triples` (corner indices into the mesh's flat corner array) against `mesh`.
    ///
    /// Each triple must name three distinct corners of one face; every face must get exactly
    /// `corners − 2` triples that cover each polygon edge once and each diagonal from both
    /// sides (a triangulation of the polygon). Triples are re-ordered to the face's winding
    /// (the corners' cyclic order in the face), so either orientation is accepted.
    ///
    /// Errors: [`UvError::RenderTriangle`] naming the first offending triple (the first triple
    /// of a face for a wrong count or a set that does not triangulate the face).
    pub fn new(mesh: &PolyMesh<'_>, triples: &[[u32; 3]]) -> Result<Self> {
        let n_corners = mesh.n_corners();
        let n_faces = mesh.n_faces();
        let mut face_of = vec![0u32; n_corners];
        for f in 0..n_faces {
            for c in mesh.face_corners(f) {
                face_of[c] = f as u32;
            }
        }
        let err = |i: usize, t: &[u32; 3], reason: String| UvError::RenderTriangle {
            triangle: i,
            corners: [t[0] as u64, t[1] as u64, t[2] as u64],
            reason,
        };
        let mut count = vec![0u32; n_faces + 1];
        let mut first = vec![u32::MAX; n_faces];
        for (i, t) in triples.iter().enumerate() {
            if let Some(&c) = t.iter().find(|&&c| c as usize >= n_corners) {
                return Err(err(i, t, format!("corner {c} out of range (mesh has {n_corners} corners)")));
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(err(i, t, "names the same corner twice".into()));
            }
            let f = face_of[t[0] as usize];
            if let Some(&c) = t.iter().find(|&&c| face_of[c as usize] != f) {
                return Err(err(i, t, format!("corner {} is in face {f} but corner {c} is in face {}", t[0], face_of[c as usize])));
            }
            count[f as usize + 1] += 1;
            if first[f as usize] == u32::MAX {
                first[f as usize] = i as u32;
            }
        }
        for f in 0..n_faces {
            let m = mesh.face_corners(f).len() as u32;
            if count[f + 1] != m - 2 {
                let i = first[f];
                return Err(match i {
                    u32::MAX => UvError::RenderTriangle {
                        triangle: triples.len(),
                        corners: [0; 3],
                        reason: format!("face {f} ({m} corners) has no triangle; every face needs {}", m - 2),
                    },
                    i => err(
                        i as usize,
                        &triples[i as usize],
                        format!("face {f} has {m} corners and needs {} triangles, got {}", m - 2, count[f + 1]),
                    ),
                });
            }
        }
        for f in 0..n_faces {
            count[f + 1] += count[f];
        }
        let offsets = count.clone();
        let mut fill = count;
        let mut triangles = vec![[0u32; 3]; triples.len()];
        for t in triples {
            let f = face_of[t[0] as usize] as usize;
            let start = mesh.face_corners(f).start as u32;
            let mut local = [t[0] - start, t[1] - start, t[2] - start];
            // Ascending corner positions follow the face's winding.
            local.sort_unstable();
            triangles[fill[f] as usize] = local;
            fill[f] += 1;
        }
        let out = FaceTriangulation { offsets, triangles };
        // Each face: polygon edges once, diagonals once per direction.
        let mut directed: Vec<(u32, u32)> = Vec::new();
        for f in 0..n_faces {
            let m = mesh.face_corners(f).len() as u32;
            if m == 3 {
                continue;
            }
            directed.clear();
            for t in out.face(f) {
                for k in 0..3 {
                    directed.push((t[k], t[(k + 1) % 3]));
                }
            }
            directed.sort_unstable();
            let dup = directed.windows(2).any(|w| w[0] == w[1]);
            let ok = !dup
                && directed.iter().all(|&(a, b)| {
                    let boundary = (a + 1) % m == b;
                    boundary || directed.binary_search(&(b, a)).is_ok()
                })
                && (0..m).all(|a| directed.binary_search(&(a, (a + 1) % m)).is_ok());
            if !ok {
                let i = first[f] as usize;
                return Err(err(i, &triples[i], format!("the triangles of face {f} do not triangulate it")));
            }
        }
        Ok(out)
    }

    /// Triangles of face `f` over its corner positions `0..corners`, in the face's winding.
    pub fn face(&self, f: usize) -> &[[u32; 3]] {
        &self.triangles[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_faces() -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
        // A quad 0-1-2-3 and a pentagon 1-4-5-6-2.
        let p = vec![
            [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0], [2.5, 0.5, 0.0], [2.0, 1.0, 0.0],
        ];
        (p, vec![0, 1, 2, 3, 1, 4, 5, 6, 2], vec![4, 5])
    }

    #[test]
    fn valid_triples_in_either_orientation_are_accepted_and_reordered() {
        let (p, cv, fs) = two_faces();
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        let tri = FaceTriangulation::new(&m, &[[5, 4, 8], [0, 1, 3], [1, 2, 3], [5, 6, 8], [6, 7, 8]]).unwrap();
        assert_eq!(tri.face(0), &[[0, 1, 3], [1, 2, 3]]);
        assert_eq!(tri.face(1), &[[0, 1, 4], [1, 2, 4], [2, 3, 4]]);
    }

    #[test]
    fn bad_triples_name_the_triple() {
        let (p, cv, fs) = two_faces();
        let m = PolyMesh::new(&p, &cv, &fs).unwrap();
        let good: Vec<[u32; 3]> = vec![[0, 1, 3], [1, 2, 3], [4, 5, 8], [5, 6, 8], [6, 7, 8]];
        let check = |t: Vec<[u32; 3]>, idx: usize, needle: &str| match FaceTriangulation::new(&m, &t) {
            Err(UvError::RenderTriangle { triangle, reason, .. }) => {
                assert_eq!(triangle, idx, "{reason}");
                assert!(reason.contains(needle), "{reason}");
            }
            other => panic!("{other:?}"),
        };
        let mut t = good.clone();
        t[2] = [4, 5, 9];
        check(t, 2, "out of range");
        let mut t = good.clone();
        t[1] = [1, 2, 4];
        check(t, 1, "is in face");
        let mut t = good.clone();
        t.pop();
        check(t, 2, "needs 3 triangles, got 2");
        let mut t = good.clone();
        t[4] = [4, 5, 8];
        check(t, 2, "do not triangulate");
        let mut t = good;
        t[0] = [0, 0, 3];
        check(t, 0, "same corner twice");
    }
}
