//! AMD vs nested dissection for sparse Cholesky on the largest chart of a mesh, subdivided
//! 1→4 zero, one and two times:
//! `cargo run --release --example ordering -- ../shared/meshes/camelhead.off [LEVELS] [REPEATS]`
//! (`ORDERING_MIN_LEVEL=K` in the environment skips the levels below K).
//!
//! For the chart's vertex-graph Laplacian plus identity (the pattern of the complex LSCM,
//! harmonic and Tutte systems) and its 2×2-block version (the pattern of the real u,v systems
//! of ARAP / SLIM / MIPS) it prints, per ordering: nnz(L) (simplicial count), the values faer
//! stores with its automatic simplicial/supernodal choice, that choice, and the medians of the
//! ordering, symbolic and numeric seconds (sequential, as `unwrap` runs them), the numeric
//! factorization both into buffers allocated once and into freshly allocated ones.
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering};
use faer::sparse::linalg::SupernodalThreshold;
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::solvers::ordering::{fill_reducing, OrderingKind};

fn median(mut t: Vec<f64>) -> f64 {
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}


/// Lower triangle (with diagonal) of `L + I` for the graph of `triangles`, each vertex
/// expanded to a `block × block` dense block.
fn system(n: usize, triangles: &[[u32; 3]], block: usize) -> (usize, Vec<usize>, Vec<usize>, Vec<f64>) {
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            nb[a.min(b)].push(a.max(b));
        }
    }
    let m = n * block;
    let (mut col_ptr, mut row_idx, mut val) = (vec![0usize], Vec::new(), Vec::new());
    for v in 0..n {
        nb[v].sort_unstable();
        nb[v].dedup();
        for bc in 0..block {
            for br in bc..block {
                row_idx.push(v * block + br);
                val.push(if br == bc { 1.0 + 8.0 } else { 0.5 });
            }
            for &w in &nb[v] {
                for br in 0..block {
                    row_idx.push(w * block + br);
                    val.push(if br == bc { -1.0 } else { 0.1 });
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    (m, col_ptr, row_idx, val)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("mesh path");
    let max_levels: usize = args.next().map(|a| a.parse().unwrap()).unwrap_or(2);
    let repeats: usize = args.next().map(|a| a.parse().unwrap()).unwrap_or(3);
    faer::set_global_parallelism(faer::Par::Seq);
    let mut s = common::load(std::path::Path::new(&path));
    println!("| triangles | system | n | ordering | nnz(L) | faer layout (stored values) | ordering s | symbolic s | numeric s | numeric s, fresh buffers | numeric s, 2 threads |");
    println!("|---:|---|---:|---|---:|---|---:|---:|---:|---:|---:|");
    let min_level: usize = std::env::var("ORDERING_MIN_LEVEL").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
    for level in 0..=max_levels {
        if level > 0 {
            s = common::subdivide(&s);
        }
        if level < min_level {
            continue;
        }
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let charts = build_charts(&mesh, &[], None);
        let c = charts.iter().max_by_key(|c| c.triangles.len()).unwrap();
        for (block, name) in [(1, "vertex graph"), (2, "2×2 blocks")] {
            let (n, col_ptr, row_idx, val) = system(c.positions.len(), &c.triangles, block);
            let a = faer::sparse::SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
            for kind in [OrderingKind::Amd, OrderingKind::NestedDissection] {
                let mut t_ord = Vec::new();
                let mut perm = None;
                for _ in 0..repeats {
                    let t = Instant::now();
                    perm = Some(fill_reducing(kind, n, &col_ptr, &row_idx).unwrap());
                    t_ord.push(t.elapsed().as_secs_f64());
                }
                let p = perm.unwrap();
                let pr = faer::perm::PermRef::new_checked(&p.fwd, &p.inv, n);
                let simplicial = factorize_symbolic_cholesky(
                    a,
                    faer::Side::Lower,
                    SymmetricOrdering::Custom(pr),
                    CholeskySymbolicParams { supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL, ..Default::default() },
                )
                .unwrap();
                let nnz_l = simplicial.len_val();
                let mut t_sym = Vec::new();
                let mut sym = None;
                for _ in 0..repeats {
                    let t = Instant::now();
                    sym = Some(factorize_symbolic_cholesky(a, faer::Side::Lower, SymmetricOrdering::Custom(pr), Default::default()).unwrap());
                    t_sym.push(t.elapsed().as_secs_f64());
                }
                let sym = sym.unwrap();
                let layout = match sym.raw() {
                    SymbolicCholeskyRaw::Simplicial(_) => "simplicial",
                    SymbolicCholeskyRaw::Supernodal(_) => "supernodal",
                };
                let mut l = vec![0.0f64; sym.len_val()];
                let req = sym.factorize_numeric_llt_scratch::<f64>(faer::Par::Seq, Default::default());
                let mut mem = faer::dyn_stack::MemBuffer::new(req);
                let mat = faer::sparse::SparseColMatRef::new(a, &val);
                let mut t_num = Vec::new();
                for _ in 0..repeats {
                    let t = Instant::now();
                    sym.factorize_numeric_llt(
                        &mut l,
                        mat,
                        faer::Side::Lower,
                        Default::default(),
                        faer::Par::Seq,
                        faer::dyn_stack::MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .unwrap();
                    t_num.push(t.elapsed().as_secs_f64());
                }
                // The same factorization on two threads (faer's parallel supernodal kernel).
                let par = faer::Par::rayon(2);
                let mut mem2 = faer::dyn_stack::MemBuffer::new(sym.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
                let mut t_par = Vec::new();
                for _ in 0..repeats {
                    let t = Instant::now();
                    sym.factorize_numeric_llt(&mut l, mat, faer::Side::Lower, Default::default(), par, faer::dyn_stack::MemStack::new(&mut mem2), Default::default())
                        .unwrap();
                    t_par.push(t.elapsed().as_secs_f64());
                }
                // The same factorization with the factor's values and the scratch allocated anew
                // each time (what faer's `Llt::try_new_with_symbolic` does per refactor).
                let mut t_fresh = Vec::new();
                for _ in 0..repeats {
                    let t = Instant::now();
                    let mut l = vec![0.0f64; sym.len_val()];
                    let mut mem = faer::dyn_stack::MemBuffer::new(req);
                    sym.factorize_numeric_llt(
                        &mut l,
                        mat,
                        faer::Side::Lower,
                        Default::default(),
                        faer::Par::Seq,
                        faer::dyn_stack::MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .unwrap();
                    std::hint::black_box(&l);
                    t_fresh.push(t.elapsed().as_secs_f64());
                }
                println!(
                    "| {} | {name} | {n} | {} | {nnz_l} | {layout} ({}) | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |",
                    c.triangles.len(),
                    if kind == OrderingKind::Amd { "AMD" } else { "ND" },
                    sym.len_val(),
                    median(t_ord),
                    median(t_sym),
                    median(t_num),
                    median(t_fresh),
                    median(t_par)
                );
            }
        }
    }
}
