//! Parallel or sequential (ours): which way the refinement runs, chosen from measured throughput.
//!
//! The parallel sections of the refinement (conflict-zone searches beside the processing of
//! the last batch, facet tests, circumcenters) pay off when the threads run on cores of their
//! own. When they do not (other work keeps the cores busy, or a VM's virtual CPUs share a
//! physical core), the parallel run is slower than a sequential one: on the 2-vCPU bench
//! machine, in phases lasting seconds, 2 threads took 0.155 s where a sequential run took
//! 0.137 s (and 0.10 s outside those phases).
//!
//! The tuner works in windows of about [`WINDOW`] insertions. In an *exploring* window the
//! batches alternate between the two modes in blocks of [`BLOCK`] batches, and the time per
//! insertion of each mode is summed over its blocks: the two measures see the same stage of
//! the run (the cost per insertion drifts as the run goes on, so windows measured at
//! different times do not compare). The first batch of a block is left out of the sums: it
//! pays for the previous block's mode (after a parallel section, rayon's idle workers spin
//! for a while before they sleep, and on a shared core that slows the next batch down). The
//! faster mode then runs the next [`EXPLOIT_WINDOWS`] windows, and the tuner explores again.
//! Only the speed depends on it: the refinement computes the same thing in both modes (see
//! `crate::schedule`), so the mesh is the same whatever the mode of each batch.

use std::time::Duration;

/// Insertions per window (about 5-10 ms of refinement).
pub(crate) const WINDOW: usize = 1024;

/// Windows run in the chosen mode between two exploring windows.
pub(crate) const EXPLOIT_WINDOWS: u32 = 8;

/// Batches per block of one mode in an exploring window.
pub(crate) const BLOCK: u32 = 4;

/// See the module docs.
///
/// Invariant: `parallel()` is false when there is one thread.
#[derive(Clone, Debug)]
pub(crate) struct Tuner {
    enabled: bool,
    /// The mode of the current batch.
    cur: bool,
    /// The mode chosen by the last exploring window.
    chosen: bool,
    exploring: bool,
    /// Insertions in the current window.
    insertions: usize,
    /// Exploitation windows since the last exploring one.
    since_explore: u32,
    /// Batches run in the current block (exploring window).
    in_block: u32,
    /// In the exploring window, per mode `[sequential, parallel]`: (seconds, insertions).
    acc: [(f64, usize); 2],
    /// Batches run in each mode, `[sequential, parallel]`.
    pub batches: [u64; 2],
}

impl Tuner {
    /// A tuner for a pool of `threads` threads. With one thread every batch is sequential;
    /// with several and `adaptive` false every batch is parallel.
    pub fn new(threads: usize, adaptive: bool) -> Tuner {
        Tuner {
            enabled: threads > 1 && adaptive,
            cur: threads > 1,
            chosen: threads > 1,
            exploring: threads > 1 && adaptive,
            insertions: 0,
            since_explore: 0,
            in_block: 0,
            acc: [(0.0, 0); 2],
            batches: [0; 2],
        }
    }

    /// Whether the parallel sections of the current batch run on several threads.
    #[inline]
    pub fn parallel(&self) -> bool {
        self.cur
    }

    /// A batch of `n` insertions took `dt` (in the mode of `parallel()`): account for it and
    /// set the mode of the next batch.
    pub fn end_batch(&mut self, n: usize, dt: Duration) {
        self.batches[usize::from(self.cur)] += 1;
        if !self.enabled {
            return;
        }
        self.insertions += n;
        if self.exploring {
            if self.in_block > 0 {
                let a = &mut self.acc[usize::from(self.cur)];
                a.0 += dt.as_secs_f64();
                a.1 += n;
            }
            self.in_block += 1;
        }
        if self.insertions >= WINDOW {
            self.insertions = 0;
            if self.exploring {
                self.exploring = false;
                self.since_explore = 0;
                let per = |(s, n): (f64, usize)| if n > 0 { s / n as f64 } else { f64::INFINITY };
                let (seq, par) = (per(self.acc[0]), per(self.acc[1]));
                // Ties (also a window without either mode: both infinite): parallel.
                self.chosen = par <= seq;
                self.acc = [(0.0, 0); 2];
            } else {
                self.since_explore += 1;
                self.exploring = self.since_explore >= EXPLOIT_WINDOWS;
                self.in_block = 0;
            }
        }
        if !self.exploring {
            self.cur = self.chosen;
        } else if self.in_block >= BLOCK {
            self.cur = !self.cur;
            self.in_block = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Batches of 32 insertions whose time depends on the mode and the batch number: returns
    /// the mode of each batch.
    fn run(t: &mut Tuner, batches: usize, cost_us: impl Fn(bool, usize) -> f64) -> Vec<bool> {
        (0..batches)
            .map(|b| {
                let p = t.parallel();
                t.end_batch(32, Duration::from_secs_f64(cost_us(p, b) * 1e-6));
                p
            })
            .collect()
    }

    #[test]
    fn one_thread_or_not_adaptive_never_changes() {
        let mut t = Tuner::new(1, true);
        let modes = run(&mut t, 200, |p, _| if p { 1.0 } else { 9.0 });
        assert!(modes.iter().all(|&p| !p));
        assert_eq!(t.batches, [200, 0]);
        let mut t = Tuner::new(4, false);
        let modes = run(&mut t, 200, |p, _| if p { 9.0 } else { 1.0 });
        assert!(modes.iter().all(|&p| p));
        assert_eq!(t.batches, [0, 200]);
    }

    #[test]
    fn picks_the_faster_mode_and_keeps_checking() {
        // 32 batches per window: the first window alternates, then EXPLOIT_WINDOWS windows of
        // the winner.
        let per_window = WINDOW / 32;
        let cycle = per_window * (1 + EXPLOIT_WINDOWS as usize);
        for par_faster in [true, false] {
            let mut t = Tuner::new(2, true);
            let modes = run(
                &mut t,
                3 * cycle,
                |p, _| if p == par_faster { 5.0 } else { 7.0 },
            );
            for c in 0..3 {
                let explore = &modes[c * cycle..c * cycle + per_window];
                assert_eq!(explore.iter().filter(|&&p| p).count(), per_window / 2);
                // In blocks of BLOCK batches.
                for b in explore.chunks(BLOCK as usize) {
                    assert!(b.iter().all(|&p| p == b[0]), "{explore:?}");
                }
                let exploit = &modes[c * cycle + per_window..(c + 1) * cycle];
                assert!(exploit.iter().all(|&p| p == par_faster), "cycle {c}");
            }
        }
    }

    /// The cost per insertion drifts (here it doubles over each window): alternating batches
    /// still tell the faster mode, where comparing whole windows would not.
    #[test]
    fn drift_does_not_fool_it() {
        let per_window = WINDOW / 32;
        let mut t = Tuner::new(2, true);
        let modes = run(&mut t, 2 * per_window, |p, b| {
            let drift = 1.0 + (b % per_window) as f64 / per_window as f64;
            drift * if p { 10.0 } else { 9.0 }
        });
        assert!(modes[per_window..].iter().all(|&p| !p));
    }
}
