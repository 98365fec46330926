//! Scheduling the refinement of section 6.1 (ours): batches of insertions (`batch`), and
//! where the parallel sections run: on several threads or on one (`tuner`, [`Exec`]).
//!
//! Every parallel section is written once, through [`Exec`]: its sequential and parallel
//! forms compute the same values in the same order, so the mesh never depends on the mode
//! (nor on the thread count); only the speed does.

pub(crate) mod batch;
pub(crate) mod tuner;

use rayon::prelude::*;
use std::time::Duration;
use tuner::Tuner;

/// How one section runs: sequentially, or on rayon's threads. Each method returns the same
/// values, in the same order, either way.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Exec {
    parallel: bool,
}

impl Exec {
    /// On rayon's threads iff `parallel`.
    pub fn new(parallel: bool) -> Exec {
        Exec { parallel }
    }

    /// `items.map(f)`, collected in order.
    pub fn map<T: Sync, R: Send>(self, items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
        if self.parallel {
            items.par_iter().map(f).collect()
        } else {
            items.iter().map(f).collect()
        }
    }

    /// [`Exec::map`] with a scratch value made by `init` (one per thread, reused across items).
    pub fn map_init<T: Sync, R: Send, S>(
        self,
        items: &[T],
        init: impl Fn() -> S + Sync + Send,
        f: impl Fn(&mut S, &T) -> R + Sync + Send,
    ) -> Vec<R> {
        if self.parallel {
            items.par_iter().map_init(init, f).collect()
        } else {
            let mut scratch = init();
            items.iter().map(|x| f(&mut scratch, x)).collect()
        }
    }

    /// `f(a[i], &mut b[i])` for every `i < a.len()` (`b` at least as long), collected in order.
    pub fn map_zip_mut<A: Sync, B: Send, R: Send>(
        self,
        a: &[A],
        b: &mut [B],
        f: impl Fn(&A, &mut B) -> R + Sync + Send,
    ) -> Vec<R> {
        if self.parallel {
            a.par_iter()
                .zip(b.par_iter_mut())
                .map(|(x, y)| f(x, y))
                .collect()
        } else {
            a.iter().zip(b.iter_mut()).map(|(x, y)| f(x, y)).collect()
        }
    }

    /// The outputs of `f` on consecutive chunks of `items` (of `chunk` items when parallel,
    /// all at once when not), concatenated in order: the same as `f(items, &mut out)` when
    /// `f` handles each item on its own.
    pub fn flat_map_chunks<T: Sync, R: Send>(
        self,
        items: &[T],
        chunk: usize,
        f: impl Fn(&[T], &mut Vec<R>) + Sync + Send,
    ) -> Vec<R> {
        let mut out = Vec::new();
        if self.parallel {
            let parts: Vec<Vec<R>> = items
                .par_chunks(chunk)
                .map(|c| {
                    let mut v = Vec::new();
                    f(c, &mut v);
                    v
                })
                .collect();
            for v in parts {
                out.extend(v);
            }
        } else {
            f(items, &mut out);
        }
        out
    }

    /// `(a(), b())`: side by side when parallel, else `a` first (and dropped, with whatever
    /// it captured, before `b` runs).
    pub fn join<RA: Send, RB: Send>(
        self,
        a: impl FnOnce() -> RA + Send,
        b: impl FnOnce() -> RB + Send,
    ) -> (RA, RB) {
        if self.parallel {
            rayon::join(a, b)
        } else {
            let ra = a();
            (ra, b())
        }
    }
}

/// Running mean of the wall time of one oracle call (over the last ~thousand batches).
/// Only used to choose between a sequential and a parallel batch, never for results.
#[derive(Clone, Copy, Debug, Default)]
struct CostEstimate {
    ns: f64,
    calls: f64,
}

impl CostEstimate {
    fn observe(&mut self, dt: Duration, n: usize) {
        const DECAY: f64 = 0.999;
        self.ns = self.ns * DECAY + dt.as_nanos() as f64;
        self.calls = self.calls * DECAY + n as f64;
    }
    fn ns_per_call(&self) -> f64 {
        if self.calls > 0.0 {
            self.ns / self.calls
        } else {
            0.0
        }
    }
}

/// Circumcenters of at least this many created cells (and facet preparations) are computed
/// in parallel.
const PARALLEL_CELLS: usize = 256;
/// Size-field evaluations from which [`Policy::field`] runs them in parallel (a field of the
/// adaptive mode costs a few microseconds a call: 16 calls pay rayon's fork-join).
const PARALLEL_FIELD: usize = 16;

/// A batch of oracle calls runs in parallel when it is expected to take longer than this.
const PARALLEL_BATCH_NS: f64 = 20_000.0;

/// Which oracle calls a section makes (each kind has its measured cost).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Calls {
    /// `Surface::value` at Voronoi vertices.
    Values,
    /// Crossings of Voronoi edges.
    Crossings,
}

/// The parallel policy: the tuner's mode, and the measured costs of oracle calls.
///
/// Invariant: every `Exec` it returns is sequential when the tuner's mode is (always, on one
/// thread).
#[derive(Clone, Debug)]
pub(crate) struct Policy {
    /// Whether the parallel sections run on several threads now (see [`tuner`]).
    pub tuner: Tuner,
    value_cost: CostEstimate,
    crossing_cost: CostEstimate,
    /// Oracle sections that ran in parallel (`Stats::parallel_oracle_batches`).
    pub parallel_oracle_batches: u64,
}

impl Policy {
    /// The policy on rayon's current pool.
    pub fn new() -> Policy {
        Policy {
            tuner: Tuner::new(rayon::current_num_threads(), true),
            value_cost: CostEstimate::default(),
            crossing_cost: CostEstimate::default(),
            parallel_oracle_batches: 0,
        }
    }

    /// The mode of the current batch (conflict-zone searches, output measures).
    pub fn batch(&self) -> Exec {
        Exec::new(self.tuner.parallel())
    }

    /// For `n` evaluations of a size field (`crate::Sizing::Field`, e.g. a nearest-point
    /// query, microseconds each): parallel from `PARALLEL_FIELD`.
    pub fn field(&self, n: usize) -> Exec {
        Exec::new(n >= PARALLEL_FIELD && self.tuner.parallel())
    }

    /// For a section of `n` cells or facets (no oracle call): parallel from `PARALLEL_CELLS`.
    pub fn cells(&self, n: usize) -> Exec {
        Exec::new(n >= PARALLEL_CELLS && self.tuner.parallel())
    }

    /// For `n` oracle calls of kind `calls`: parallel only when there are several threads,
    /// and the calls take long enough (by their measured cost) to pay rayon's fork-join, a
    /// few microseconds. Counted in `parallel_oracle_batches`.
    pub fn oracle(&mut self, n: usize, calls: Calls) -> Exec {
        let cost = match calls {
            Calls::Values => self.value_cost,
            Calls::Crossings => self.crossing_cost,
        };
        let parallel =
            n >= 2 && self.tuner.parallel() && cost.ns_per_call() * n as f64 > PARALLEL_BATCH_NS;
        self.parallel_oracle_batches += parallel as u64;
        Exec::new(parallel)
    }

    /// `n` oracle calls of kind `calls` took `dt`.
    pub fn observe(&mut self, calls: Calls, dt: Duration, n: usize) {
        match calls {
            Calls::Values => self.value_cost.observe(dt, n),
            Calls::Crossings => self.crossing_cost.observe(dt, n),
        }
    }
}
