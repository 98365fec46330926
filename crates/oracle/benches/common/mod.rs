//! Shared by the oracle benches: one timed query per iteration, cycling through a query set.

use criterion::Bencher;
use std::hint::black_box;

/// A bench routine timing `f(q)` for the queries `qs` in turn, one per iteration (in order,
/// starting at the second and wrapping around), so that no single query's cache state
/// decides the figure.
pub fn cycling<'a, T: Copy, R>(
    qs: &'a [T],
    mut f: impl FnMut(T) -> R + 'a,
) -> impl FnMut(&mut Bencher) + 'a {
    let mut i = 0;
    move |b: &mut Bencher| {
        b.iter(|| {
            i = (i + 1) % qs.len();
            black_box(f(black_box(qs[i])))
        })
    }
}
