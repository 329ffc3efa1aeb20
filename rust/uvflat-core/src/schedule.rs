//! Chart scheduling: map every chart in parallel, largest first, tiny charts batched, results
//! in chart-id order.

use rayon::prelude::*;

use crate::charts::Chart;

/// Charts of at most this many triangles are solved in batches of [`TINY_CHART_BATCH`] per
/// rayon task, so that per-task overhead does not dominate meshes cut into thousands of
/// one-face charts.
const TINY_CHART_TRIANGLES: usize = 8;
/// Number of tiny charts per rayon task.
const TINY_CHART_BATCH: usize = 256;

/// Run `solve` on every chart in parallel and return the results in chart-id order.
///
/// Scheduling: charts sorted by triangle count, largest first (stable, so ties keep id order),
/// each non-tiny chart its own rayon task, so the longest solves start first and the tail of the
/// run is filled with small charts; tiny charts run in batches. Each chart's result depends only
/// on the chart (factorizations inside a chart are sequential), so the output is identical for
/// any thread count.
pub(crate) fn solve_charts_scheduled<R: Send>(charts: &[Chart], solve: impl Fn(usize, &Chart) -> R + Sync) -> Vec<R> {
    let mut order: Vec<usize> = (0..charts.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(charts[i].triangles.len()));
    let n_big = order.partition_point(|&i| charts[i].triangles.len() > TINY_CHART_TRIANGLES);
    let (big, tiny) = order.split_at(n_big);
    let tasks: Vec<&[usize]> = big.chunks(1).chain(tiny.chunks(TINY_CHART_BATCH)).collect();
    let done: Vec<(usize, R)> = tasks
        .par_iter()
        .with_max_len(1)
        .flat_map_iter(|task| task.iter().map(|&id| (id, solve(id, &charts[id]))))
        .collect();
    let mut slots: Vec<Option<R>> = std::iter::repeat_with(|| None).take(charts.len()).collect();
    for (id, r) in done {
        slots[id] = Some(r);
    }
    slots.into_iter().map(|r| r.expect("every chart is solved exactly once")).collect()
}
