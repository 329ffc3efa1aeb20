//! The polygon edge graph of one chart: what automatic cuts walk on.
//!
//! Cuts follow polygon edges only (never the diagonals the core adds to triangulate n-gons), so
//! this graph is built from the chart's polygons, not from its triangles: vertices are chart
//! vertices, edges are polygon edges, and the dual graph's nodes are the polygons.

use crate::charts::Chart;
use crate::geometry::{cross, dot, newell_normal, norm, sub, unit};
use crate::mesh::PolyMesh;

/// Polygon edge graph of a chart, with per-edge cut costs.
#[derive(Debug, Clone)]
pub struct ChartGraph {
    /// Number of chart vertices.
    pub n_vertices: usize,
    /// Polygons over chart vertices, in the chart's face order.
    pub polygons: Vec<Vec<u32>>,
    /// Undirected polygon edges `[a, b]` with `a < b`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// The one or two polygons beside each edge (`u32::MAX` where there is none: a boundary edge).
    pub edge_polygons: Vec<[u32; 2]>,
    /// 3D length of every edge.
    pub length: Vec<f64>,
    /// Angle between the normals of the two polygons beside each edge (0 for flat or boundary).
    pub dihedral: Vec<f64>,
    /// Whether the surface folds inward across each edge (a valley seen from the side the
    /// polygons' winding faces; `false` for convex, flat and boundary edges).
    pub concave: Vec<bool>,
    /// CSR adjacency: the neighbours of vertex `v` are `adj[adj_start[v]..adj_start[v + 1]]`
    /// as `(neighbour, edge id)`, in ascending neighbour order (deterministic walks).
    pub adj_start: Vec<usize>,
    pub adj: Vec<(u32, u32)>,
}

/// The faces of `chart` (polygons of `mesh`) as polygons over chart vertices, in the chart's
/// face order.
pub fn face_polygons(mesh: &PolyMesh<'_>, chart: &Chart) -> Vec<Vec<u32>> {
    let mut polygons = Vec::with_capacity(chart.faces.len());
    let mut at = 0usize;
    for &f in &chart.faces {
        let m = mesh.face_corners(f as usize).len();
        polygons.push(chart.corner_vertex[at..at + m].iter().map(|&(_, v)| v).collect::<Vec<u32>>());
        at += m;
    }
    polygons
}

/// Unit normal of every polygon (over chart vertices) of `chart`: Newell's normal, robust for
/// non-planar polygons; zero for a polygon without area.
pub fn polygon_normals(chart: &Chart, polygons: &[Vec<u32>]) -> Vec<[f64; 3]> {
    polygons
        .iter()
        .map(|poly| unit(newell_normal(poly.len(), |i| chart.positions[poly[i] as usize])))
        .collect()
}

impl ChartGraph {
    /// The edges flagged in `cut` (one flag per edge) as sorted mesh vertex pairs of `chart`
    /// (the chart this graph was made of): the seams a cut adds.
    pub fn mesh_seams(&self, chart: &Chart, cut: &[bool]) -> Vec<[u32; 2]> {
        let mut seams: Vec<[u32; 2]> = (0..self.edges.len())
            .filter(|&e| cut[e])
            .map(|e| {
                let [a, b] = self.edges[e];
                let (ma, mb) = (chart.mesh_vertex[a as usize], chart.mesh_vertex[b as usize]);
                [ma.min(mb), ma.max(mb)]
            })
            .collect();
        seams.sort_unstable();
        seams.dedup();
        seams
    }

    /// Build the graph of `chart`, whose faces are polygons of `mesh`.
    pub fn new(mesh: &PolyMesh<'_>, chart: &Chart) -> ChartGraph {
        let polygons = face_polygons(mesh, chart);
        let normals = polygon_normals(chart, &polygons);
        // Every polygon side keyed by its vertex pair, sorted (then by polygon, so the first
        // polygon of an edge is the one met first): edge ids in vertex-pair order.
        let mut sides: Vec<(u64, u32)> = Vec::with_capacity(polygons.iter().map(Vec::len).sum());
        for (p, poly) in polygons.iter().enumerate() {
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                sides.push((((a.min(b) as u64) << 32) | a.max(b) as u64, p as u32));
            }
        }
        sides.sort_unstable();
        let mut edges: Vec<[u32; 2]> = Vec::with_capacity(sides.len() / 2 + 1);
        let mut edge_polygons: Vec<[u32; 2]> = Vec::with_capacity(sides.len() / 2 + 1);
        for (k, &(key, p)) in sides.iter().enumerate() {
            if k > 0 && sides[k - 1].0 == key {
                // A later polygon of the same edge (the last one on a non-manifold edge).
                edge_polygons.last_mut().expect("an edge")[1] = p;
            } else {
                edges.push([(key >> 32) as u32, key as u32]);
                edge_polygons.push([p, u32::MAX]);
            }
        }
        drop(sides);
        let length: Vec<f64> = edges
            .iter()
            .map(|e| norm(sub(chart.positions[e[1] as usize], chart.positions[e[0] as usize])))
            .collect();
        let dihedral: Vec<f64> = edge_polygons
            .iter()
            .map(|p| {
                if p[1] == u32::MAX {
                    return 0.0;
                }
                let (a, b) = (normals[p[0] as usize], normals[p[1] as usize]);
                let c = norm(cross(a, b));
                c.atan2(dot(a, b)).abs()
            })
            .collect();
        // Convex when the normals diverge: (n₀ − n₁)·(c₀ − c₁) > 0 for the polygons' normals
        // and centroids (a ridge's normals lean away from each other).
        let centroids: Vec<[f64; 3]> = polygons
            .iter()
            .map(|poly| {
                let mut c = [0.0; 3];
                for &v in poly {
                    let p = chart.positions[v as usize];
                    for k in 0..3 {
                        c[k] += p[k] / poly.len() as f64;
                    }
                }
                c
            })
            .collect();
        let concave: Vec<bool> = edge_polygons
            .iter()
            .map(|p| {
                if p[1] == u32::MAX || p[0] == p[1] {
                    return false;
                }
                let (a, b) = (p[0] as usize, p[1] as usize);
                dot(sub(normals[a], normals[b]), sub(centroids[a], centroids[b])) < 0.0
            })
            .collect();
        let n = chart.positions.len();
        let mut deg = vec![0usize; n + 1];
        for e in &edges {
            deg[e[0] as usize] += 1;
            deg[e[1] as usize] += 1;
        }
        let mut adj_start = vec![0usize; n + 1];
        for v in 0..n {
            adj_start[v + 1] = adj_start[v] + deg[v];
        }
        let mut fill = adj_start.clone();
        let mut adj = vec![(0u32, 0u32); adj_start[n]];
        for (id, e) in edges.iter().enumerate() {
            adj[fill[e[0] as usize]] = (e[1], id as u32);
            fill[e[0] as usize] += 1;
            adj[fill[e[1] as usize]] = (e[0], id as u32);
            fill[e[1] as usize] += 1;
        }
        for v in 0..n {
            adj[adj_start[v]..adj_start[v + 1]].sort_unstable();
        }
        ChartGraph { n_vertices: n, polygons, edges, edge_polygons, length, dihedral, concave, adj_start, adj }
    }

    /// `(neighbour, edge id)` of vertex `v`.
    #[inline]
    pub fn neighbours(&self, v: u32) -> &[(u32, u32)] {
        &self.adj[self.adj_start[v as usize]..self.adj_start[v as usize + 1]]
    }

    /// Whether edge `e` has a polygon on one side only.
    #[inline]
    pub fn is_boundary(&self, e: usize) -> bool {
        self.edge_polygons[e][1] == u32::MAX
    }
}

/// Dijkstra from several sources at once over edge weights `cost`.
///
/// Returns `(distance, parent edge, source label)` per vertex (`u32::MAX` for none). Ties are
/// broken by vertex id, so the result is deterministic. `label_of_source[k]` labels the
/// sources of `sources[k]`.
pub fn multi_source_dijkstra(graph: &ChartGraph, cost: &[f64], sources: &[(u32, u32)]) -> (Vec<f64>, Vec<u32>, Vec<u32>) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    #[derive(PartialEq, PartialOrd)]
    struct Key(f64);
    impl Eq for Key {}
    impl Ord for Key {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            self.0.total_cmp(&o.0)
        }
    }
    let n = graph.n_vertices;
    let mut dist = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut label = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    for &(v, l) in sources {
        if dist[v as usize] > 0.0 || l < label[v as usize] {
            dist[v as usize] = 0.0;
            label[v as usize] = l;
            heap.push(Reverse((Key(0.0), v)));
        }
    }
    let mut done = vec![false; n];
    while let Some(Reverse((Key(d), v))) = heap.pop() {
        if done[v as usize] {
            continue;
        }
        done[v as usize] = true;
        for &(w, e) in graph.neighbours(v) {
            let nd = d + cost[e as usize];
            let wi = w as usize;
            // An infinite cost (an edge seams must avoid) is no edge at all.
            if !done[wi] && nd.is_finite() && (nd < dist[wi] || (nd == dist[wi] && label[v as usize] < label[wi])) {
                dist[wi] = nd;
                parent[wi] = e;
                label[wi] = label[v as usize];
                heap.push(Reverse((Key(nd), w)));
            }
        }
    }
    (dist, parent, label)
}

/// The other end of edge `e` seen from `v`.
#[inline]
pub fn other(graph: &ChartGraph, e: u32, v: u32) -> u32 {
    let [a, b] = graph.edges[e as usize];
    if a == v {
        b
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 × 4 grid of unit cells as polygons: cell (0, 0) split into two triangles, cells
    /// (1, 1) and (2, 1) merged into a hexagon, every other cell a quad.
    fn mixed_grid() -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
        let n = 4u32;
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                positions.push([i as f64, j as f64, 0.1 * ((i * j) % 3) as f64]);
            }
        }
        let (mut corners, mut sizes) = (Vec::new(), Vec::new());
        for j in 0..n {
            for i in 0..n {
                match (i, j) {
                    (0, 0) => {
                        corners.extend([id(0, 0), id(1, 0), id(1, 1), id(0, 0), id(1, 1), id(0, 1)]);
                        sizes.extend([3, 3]);
                    }
                    (1, 1) => {
                        corners.extend([id(1, 1), id(2, 1), id(3, 1), id(3, 2), id(2, 2), id(1, 2)]);
                        sizes.push(6);
                    }
                    (2, 1) => {}
                    _ => {
                        corners.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                        sizes.push(4);
                    }
                }
            }
        }
        (positions, corners, sizes)
    }

    #[test]
    fn every_polygon_side_is_one_edge_that_knows_its_polygons() {
        let (positions, corners, sizes) = mixed_grid();
        let mesh = PolyMesh::new(&positions, &corners, &sizes).expect("a valid mesh");
        let charts = crate::charts::build_charts(&mesh, &[], None);
        assert_eq!(charts.len(), 1);
        let chart = &charts[0];
        let g = ChartGraph::new(&mesh, chart);
        assert_eq!(g.polygons.len(), sizes.len());
        // Edge ids in vertex-pair order, each pair once.
        assert!(g.edges.iter().all(|e| e[0] < e[1]));
        assert!(g.edges.windows(2).all(|w| w[0] < w[1]));
        // A disk: V − E + F = 1, and the outline is the grid's 16 sides.
        assert_eq!(chart.positions.len() + g.polygons.len(), g.edges.len() + 1);
        assert_eq!(g.edge_polygons.iter().filter(|p| p[1] == u32::MAX).count(), 16);
        let mut sides = vec![0usize; g.edges.len()];
        for (p, poly) in g.polygons.iter().enumerate() {
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                let e = g.edges.binary_search(&[a.min(b), a.max(b)]).expect("every side is an edge");
                assert!(g.edge_polygons[e].contains(&(p as u32)), "polygon {p} missing from edge {e}");
                sides[e] += 1;
            }
        }
        for (e, pp) in g.edge_polygons.iter().enumerate() {
            // Interior edges: two polygons, the first met first; outline edges: one.
            if pp[1] == u32::MAX {
                assert_eq!(sides[e], 1);
            } else {
                assert_eq!(sides[e], 2);
                assert!(pp[0] < pp[1]);
            }
        }
    }
}
