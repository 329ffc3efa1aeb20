//! Small islands left by repair (a few faces between a hole's cut and the outline, the
//! peel's patch pieces) are laid on the islands around them where they fit
//! (`pipeline/glue.rs`): fewer islands, the same rule on every one, the seams reported still
//! exactly the islands' borders, and the outcome does not depend on threads.

mod common;

use common::{assert_islands_keep_the_rule, load, shared_meshes, with_holes, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::{unwrap, Method, UnwrapOptions};

fn main_case(seed: u64) -> Option<Soup> {
    let dir = shared_meshes()?;
    Some(with_holes(&load(&dir.join("3holes.off")), 3, 600, seed))
}

/// 3holes with three holes of 600 faces (two parts: the holes cut a sliver off): with both
/// methods, the cuts joining the holes leave 15–20 small islands, each laid back on its
/// neighbours, and at most three islands more than parts remain.
#[test]
fn small_islands_of_a_mesh_with_holes_are_laid_on_their_neighbours() {
    let Some(s) = main_case(2) else { return };
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let parts = build_charts(&mesh, &[], None).len();
    for (name, method) in [("abf", Method::Abf(Default::default())), ("slim", Method::Slim(Default::default()))] {
        let options = UnwrapOptions { method, ..Default::default() };
        let r = unwrap(&s.input(), &options).unwrap();
        assert_islands_keep_the_rule(&s, name, &r);
        assert!(r.phases.glued >= 10, "{name}: {:?}", r.phases);
        let sizes: Vec<usize> = r.charts.iter().map(|c| c.faces).collect();
        assert!(r.charts.len() <= parts + 3, "{name}: {parts} parts, islands of {sizes:?} faces");
        // The same on one thread, to the bit.
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let one = pool.install(|| unwrap(&s.input(), &options).unwrap());
        assert_eq!(one.new_seams, r.new_seams, "{name}");
        let bits = |uv: &[[f64; 2]]| uv.iter().flat_map(|p| [p[0].to_bits(), p[1].to_bits()]).collect::<Vec<u64>>();
        assert!(bits(&one.uv) == bits(&r.uv), "{name}: the UVs differ on one thread");
    }
}
