//! Minimal double-double arithmetic (error-free transformations), shared by the circumcenter
//! fallback and the in-sphere filter.

#[derive(Clone, Copy, Debug)]
pub struct D(pub f64, pub f64);

#[inline]
pub fn two_sum(a: f64, b: f64) -> D {
    let s = a + b;
    let bb = s - a;
    D(s, (a - (s - bb)) + (b - bb))
}
#[inline]
fn quick(a: f64, b: f64) -> D {
    let s = a + b;
    D(s, b - (s - a))
}
/// Exact product `a * b = hi + lo` (no overflow: |a|, |b| < 2^995), with a hardware FMA (`FMA = true`, only inside code compiled with the `fma`
/// target feature, otherwise `mul_add` is a slow library call) or Dekker's splitting.
#[inline(always)]
pub fn two_prod_with<const FMA: bool>(a: f64, b: f64) -> D {
    let p = a * b;
    if FMA {
        D(p, a.mul_add(b, -p))
    } else {
        let (ah, al) = split(a);
        let (bh, bl) = split(b);
        D(p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
    }
}
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}
impl std::ops::Add for D {
    type Output = D;
    #[inline]
    fn add(self, o: D) -> D {
        let s = two_sum(self.0, o.0);
        let t = two_sum(self.1, o.1);
        let s = quick(s.0, s.1 + t.0);
        quick(s.0, s.1 + t.1)
    }
}
impl std::ops::Neg for D {
    type Output = D;
    #[inline(always)]
    fn neg(self) -> D {
        D(-self.0, -self.1)
    }
}
impl std::ops::Sub for D {
    type Output = D;
    #[inline(always)]
    fn sub(self, o: D) -> D {
        self + (-o)
    }
}
impl std::ops::Mul for D {
    type Output = D;
    #[inline]
    fn mul(self, o: D) -> D {
        mul::<{ cfg!(target_feature = "fma") }>(self, o)
    }
}
/// Double-double product (relative error below 8 u^2), see [`two_prod_with`] for `FMA`.
#[inline(always)]
pub fn mul<const FMA: bool>(x: D, o: D) -> D {
    let p = two_prod_with::<FMA>(x.0, o.0);
    quick(p.0, p.1 + (x.0 * o.1 + x.1 * o.0))
}
/// A double times a double-double: [`mul`] with `x = D(a, 0)`, without the zero terms.
#[inline(always)]
pub fn mul_f64<const FMA: bool>(a: f64, o: D) -> D {
    let p = two_prod_with::<FMA>(a, o.0);
    quick(p.0, p.1 + a * o.1)
}
