//! Union-find (ours) with path halving; the smaller root wins, so results do not depend on the
//! order of unions.

/// Disjoint sets over `0..n` (the parent of each element).
pub(super) struct Dsu(pub Vec<u32>);
impl Dsu {
    #[inline]
    /// The root of `x`'s set.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    #[inline]
    /// Join the sets of `a` and `b`.
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}
