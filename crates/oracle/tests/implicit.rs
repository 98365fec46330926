//! Implicit backend: expression parser/compiler, ImplicitSurface checks and oracles, root
//! finding, catalog.

mod common;

use glam::DVec3;
use oracle::catalog;
use oracle::expr::{Expr, ExprErrorKind};
use oracle::implicit::{ImplicitError, ImplicitSurface, fibonacci_sphere};
use oracle::roots::{self, SplitMix64};
use oracle::{BoundingSphere, OracleError, Surface};
use proptest::prelude::*;
use std::cell::Cell;

fn ball(r: f64) -> BoundingSphere {
    BoundingSphere::at_origin(r)
}

fn ev(src: &str, p: [f64; 3]) -> f64 {
    Expr::parse(src)
        .unwrap_or_else(|e| panic!("{e}"))
        .eval(DVec3::from_array(p))
}

/// Asserts `ev(src, p) == want` for every `(src, want)` (exact: the cases are exact or use the
/// same libm call as the evaluator).
fn assert_evals(p: [f64; 3], cases: &[(&str, f64)]) {
    for &(src, want) in cases {
        assert_eq!(ev(src, p), want, "{src} at {p:?}");
    }
}

/// Asserts that `src` fails to parse with an arity error (`expected` arguments, `found` given).
fn assert_arity(src: &str, expected: usize, found: usize) {
    let kind = Expr::parse(src).unwrap_err().kind;
    let arity = match &kind {
        ExprErrorKind::Arity {
            expected, found, ..
        } => Some((*expected, *found)),
        _ => None,
    };
    assert_eq!(arity, Some((expected, found)), "{src}: {kind:?}");
}

// ---------------------------------------------------------------- parser

#[test]
fn precedence_and_associativity() {
    let p = [3.0, 2.0, -1.0];
    assert_evals(
        p,
        &[
            ("-x^2", -9.0),
            ("(-x)^2", 9.0),
            ("2^3^2", 512.0),
            ("1-2-3", -4.0),
            ("8/4/2", 1.0),
            ("2+3*4", 14.0),
            ("(2+3)*4", 20.0),
            ("x^-1", 1.0 / 3.0),
            ("2**3", 8.0),
            ("- - x", 3.0),
            ("+y", 2.0),
            ("2*-y", -4.0),
            ("-2^-2", -0.25),
            ("x*y^2*z", -12.0),
            ("x^2/y^2", 2.25),
        ],
    );
}

#[test]
fn numbers_constants_functions() {
    let p = [0.5, -2.0, 4.0];
    assert_evals(
        p,
        &[
            ("1e-3*1000", 1.0),
            ("2.5E+2", 250.0),
            (".5+.5", 1.0),
            ("pi", std::f64::consts::PI),
            ("sqrt(z)", 2.0),
            ("cbrt(-8)", -2.0),
            ("ln(exp(2))", 2.0),
            ("log(z)", 4f64.ln()),
            ("abs(y)", 2.0),
            ("sign(y) + sign(0) + sign(x)", 0.0),
            ("min(x, y)", -2.0),
            ("max(x, y)", 0.5),
            ("pow(2, 10)", 1024.0),
            ("pow(z, 0.5)", 2.0),
        ],
    );
    assert_eq!(
        ev("sin(x)^2+cos(x)^2", p),
        0.5f64.sin().powi(2) + 0.5f64.cos().powi(2)
    );
    assert_eq!(ev("tan(x)", p), 0.5f64.tan());
    assert_eq!(ev("atan(x)", p), 0.5f64.atan());
    assert!(ev("sqrt(y)", p).is_nan());
    assert!(
        ev("y^0.3", p).is_nan(),
        "non-integer power of a negative number is NaN"
    );
}

#[test]
fn compilation_folds_and_shares() {
    // x^2 appears three times, y^2 twice: shared; constants folded.
    let e = Expr::parse("(x^2+y^2+z^2+1-0.09)^2-4*(x^2+y^2) + 0*(2+3)").unwrap();
    assert!(
        e.instruction_count() <= 12,
        "{} instructions",
        e.instruction_count()
    );
    let c = Expr::parse("2*pi*(3+4)^2").unwrap();
    assert_eq!(c.instruction_count(), 0);
    assert_eq!(c.eval(DVec3::ZERO), 2.0 * std::f64::consts::PI * 49.0);
    let p = Expr::parse("x^8").unwrap();
    assert_eq!(p.instruction_count(), 3);
    assert_eq!(p.eval(DVec3::new(2.0, 0.0, 0.0)), 256.0);
}

#[test]
fn parse_error_columns_and_caret() {
    let e = Expr::parse("x^2+(y^2-1").unwrap_err();
    assert_eq!(e.column, 11);
    assert!(matches!(&e.kind, ExprErrorKind::Expected { expected, .. } if expected == "')'"));
    let msg = e.to_string();
    assert!(
        msg.starts_with("expected ')', found end of input at column 11: x^2+(y^2-1"),
        "{msg}"
    );
    // One line; `>>` marks the column (here: the end of the input).
    assert_eq!(msg.lines().count(), 1, "{msg}");
    assert!(msg.ends_with(": x^2+(y^2-1>>"), "{msg}");
    let e = Expr::parse("x^2+y^2+*z^2-1").unwrap_err();
    assert!(e.to_string().ends_with(": x^2+y^2+>>*z^2-1"), "{e}");

    let cases: &[(&str, usize)] = &[
        ("x + * y", 5),
        ("2x", 2),
        ("x # y", 3),
        ("x)", 2),
        ("(x", 3),
        ("min(x y)", 7),
        ("sqrt", 5),
        ("1e", 1),
        ("1e999", 1),
        ("", 1),
        ("   ", 4),
        ("x +", 4),
        ("x^2 + 3.1.4", 7),
    ];
    for &(src, col) in cases {
        let e = Expr::parse(src).unwrap_err();
        assert_eq!(e.column, col, "{src:?}: {e}");
        assert!(e.to_string().contains(&format!("at column {col}")), "{e}");
    }
}

#[test]
fn unknown_names_are_named() {
    let e = Expr::parse("x^2 + w").unwrap_err();
    assert_eq!(e.kind, ExprErrorKind::UnknownVariable("w".into()));
    assert_eq!(e.column, 7);
    assert!(e.to_string().contains("unknown variable 'w'"));
    let e = Expr::parse("1 + foo(x)").unwrap_err();
    assert_eq!(e.kind, ExprErrorKind::UnknownFunction("foo".into()));
    assert_eq!(e.column, 5);
    assert!(e.to_string().contains("unknown function 'foo'"));
    let e = Expr::parse("X+1").unwrap_err();
    assert_eq!(e.kind, ExprErrorKind::UnknownVariable("X".into()));
    let e = Expr::parse("x(2)").unwrap_err();
    assert_eq!(e.kind, ExprErrorKind::NotAFunction("x".into()));
    assert_arity("min(x)", 2, 1);
    assert_arity("sin(x, y)", 1, 2);
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let src = format!("{}x{}", "(".repeat(100_000), ")".repeat(100_000));
    assert_eq!(Expr::parse(&src).unwrap_err().kind, ExprErrorKind::TooDeep);
    let src = format!("{}x", "-".repeat(100_000));
    assert_eq!(Expr::parse(&src).unwrap_err().kind, ExprErrorKind::TooDeep);
    let ok = format!("{}x{}", "(".repeat(100), ")".repeat(100));
    assert_eq!(Expr::parse(&ok).unwrap().eval(DVec3::X), 1.0);
}

/// Random expression trees with an independent reference evaluation.
#[derive(Clone, Debug)]
enum T {
    Var(usize),
    Num(f64),
    Neg(Box<T>),
    Bin(char, Box<T>, Box<T>),
    PowC(Box<T>, f64),
    F1(&'static str, Box<T>),
    F2(&'static str, Box<T>, Box<T>),
}

impl T {
    fn src(&self) -> String {
        match self {
            T::Var(i) => ["x", "y", "z"][*i].to_string(),
            T::Num(v) => format!("{v:?}"),
            T::Neg(a) => format!("(-{})", a.src()),
            T::Bin(op, a, b) => format!("({}{op}{})", a.src(), b.src()),
            T::PowC(a, n) => format!("({})^({n:?})", a.src()),
            T::F1(f, a) => format!("{f}({})", a.src()),
            T::F2(f, a, b) => format!("{f}({}, {})", a.src(), b.src()),
        }
    }
    fn is_const(&self) -> bool {
        match self {
            T::Var(_) => false,
            T::Num(_) => true,
            T::Neg(a) | T::PowC(a, _) | T::F1(_, a) => a.is_const(),
            T::Bin(_, a, b) | T::F2(_, a, b) => a.is_const() && b.is_const(),
        }
    }
    /// The largest |argument| of a `sin` or `cos` in the tree at `p` (0 without them). Above
    /// about 1e3 an ulp of the argument (from powers rounded differently) is no longer small
    /// against the period, so two correct evaluators may disagree in every digit:
    /// `sin(exp(y^-2) + x)` at y = -0.0516 is sin(1.4e162), -0.046 by one and 0.99999 by
    /// the other (proptest found it, 2026-12-06; kept in `implicit.proptest-regressions`).
    fn largest_trig_argument(&self, p: [f64; 3]) -> f64 {
        match self {
            T::Var(_) | T::Num(_) => 0.0,
            T::F1(f, a) if *f == "sin" || *f == "cos" => {
                a.eval(p).abs().max(a.largest_trig_argument(p))
            }
            T::Neg(a) | T::PowC(a, _) | T::F1(_, a) => a.largest_trig_argument(p),
            T::Bin(_, a, b) | T::F2(_, a, b) => {
                a.largest_trig_argument(p).max(b.largest_trig_argument(p))
            }
        }
    }
    /// Reference: integer powers of non-constants by binary exponentiation (as documented by
    /// the compiler), everything else by the obvious f64 operation.
    fn eval(&self, p: [f64; 3]) -> f64 {
        fn powi(a: f64, n: u32) -> f64 {
            match n {
                0 => 1.0,
                1 => a,
                _ => {
                    let h = powi(a, n / 2);
                    if n % 2 == 1 { h * h * a } else { h * h }
                }
            }
        }
        match self {
            T::Var(i) => p[*i],
            T::Num(v) => *v,
            T::Neg(a) => -a.eval(p),
            T::Bin(op, a, b) => {
                let (a, b) = (a.eval(p), b.eval(p));
                match op {
                    '+' => a + b,
                    '-' => a - b,
                    '*' => a * b,
                    _ => a / b,
                }
            }
            T::PowC(a, n) => {
                let v = a.eval(p);
                if a.is_const() || n.fract() != 0.0 {
                    if *n == 0.5 { v.sqrt() } else { v.powf(*n) }
                } else if *n < 0.0 {
                    1.0 / powi(v, n.abs() as u32)
                } else {
                    powi(v, *n as u32)
                }
            }
            T::F1(f, a) => {
                let v = a.eval(p);
                match *f {
                    "sqrt" => v.sqrt(),
                    "exp" => v.exp(),
                    "ln" => v.ln(),
                    "sin" => v.sin(),
                    "cos" => v.cos(),
                    _ => v.abs(),
                }
            }
            T::F2(f, a, b) => {
                let (a, b) = (a.eval(p), b.eval(p));
                if *f == "min" { a.min(b) } else { a.max(b) }
            }
        }
    }
}

fn tree() -> impl Strategy<Value = T> {
    let leaf = prop_oneof![
        (0usize..3).prop_map(T::Var),
        (-4i32..5).prop_map(|v| T::Num(v as f64)),
        (-3.0f64..3.0).prop_map(T::Num),
    ];
    leaf.prop_recursive(5, 48, 2, |inner| {
        prop_oneof![
            inner.clone().prop_map(|a| T::Neg(Box::new(a))),
            (
                prop::sample::select(vec!['+', '-', '*', '/']),
                inner.clone(),
                inner.clone()
            )
                .prop_map(|(o, a, b)| T::Bin(o, Box::new(a), Box::new(b))),
            (
                inner.clone(),
                prop::sample::select(vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, -1.0, -2.0, 0.5, 1.5])
            )
                .prop_map(|(a, n)| T::PowC(Box::new(a), n)),
            (
                prop::sample::select(vec!["sqrt", "exp", "ln", "sin", "cos", "abs"]),
                inner.clone()
            )
                .prop_map(|(f, a)| T::F1(f, Box::new(a))),
            (
                prop::sample::select(vec!["min", "max"]),
                inner.clone(),
                inner
            )
                .prop_map(|(f, a, b)| T::F2(f, Box::new(a), Box::new(b))),
        ]
    })
}

/// Equal up to a few ulps (integer powers are evaluated as products, whose rounding can differ
/// from `powf` by an ulp or so).
fn same(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan())
        || a == b
        || (a - b).abs() <= 8.0 * f64::EPSILON * a.abs().max(b.abs())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// The compiled program (folding, sharing, powers as products) computes exactly what the
    /// tree says, to a few ulps, at random points.
    #[test]
    fn compiled_equals_reference(t in tree(), pts in prop::collection::vec(prop::array::uniform3(-2.0f64..2.0), 8)) {
        let src = t.src();
        let e = Expr::parse(&src).map_err(|e| TestCaseError::fail(e.to_string()))?;
        for p in pts {
            let (got, want) = (e.eval(DVec3::from_array(p)), t.eval(p));
            prop_assert!(same(got, want), "{src} at {p:?}: compiled {got}, reference {want}");
        }
    }

    /// Re-parsing the printed tree gives the same program (the printer is the parser's inverse
    /// on these trees) and the slow tree interpreter agrees up to rounding of powers.
    #[test]
    fn tree_interpreter_agrees(t in tree(), p in prop::array::uniform3(-2.0f64..2.0)) {
        let e = Expr::parse(&t.src()).unwrap();
        let (a, b) = (e.eval(DVec3::from_array(p)), e.eval_tree(DVec3::from_array(p)));
        // Where the value is well conditioned: finite, moderate, no trigonometric function
        // of a large argument.
        if a.is_finite() && b.is_finite() && a.abs() < 1e6 && t.largest_trig_argument(p) < 1e3 {
            prop_assert!((a - b).abs() <= 1e-6 * (1.0 + a.abs()) || (a - b).abs() < 1e-3,
                "{}: {a} vs {b}", t.src());
        }
    }

    /// Bisection and the safeguarded method land on the unit sphere to the tolerance.
    #[test]
    fn roots_hit_the_sphere(seed in any::<u64>(), sign_only in any::<bool>()) {
        let f = move |p: DVec3| {
            let v = p.length_squared() - 1.0;
            if sign_only { if v < 0.0 { -1.0 } else if v > 0.0 { 1.0 } else { 0.0 } } else { v }
        };
        let mut rng = SplitMix64(seed);
        let a = rng.unit_vector() * 0.9 * rng.next_f64();
        let b = rng.unit_vector() * 1.9;
        let tol = 1e-7 * 2.0;
        for p in [
            roots::bisect(f, roots::Ends::new(a, f(a), b, f(b)), tol),
            roots::try_find_root(f, roots::Ends::new(a, f(a), b, f(b)), tol).unwrap(),
            roots::try_find_root(f, roots::Ends::new(b, f(b), a, f(a)), tol).unwrap(),
        ] {
            prop_assert!((p.length() - 1.0).abs() <= tol, "{p} off by {}", p.length() - 1.0);
        }
    }
}

#[test]
fn gradient_is_exact() {
    let mut rng = SplitMix64(11);
    for e in catalog::entries() {
        let Some(src) = &e.expression else {
            continue; // trefoil: native gradient, tested in trefoil_is_a_tube_of_constant_radius
        };
        let x = Expr::parse(src).unwrap();
        for _ in 0..50 {
            let p = e.bounding_sphere.center
                + rng.unit_vector() * e.bounding_sphere.radius * rng.next_f64();
            let (v, g) = x.eval_grad(p);
            assert_eq!(v, x.eval(p));
            let h = 1e-6;
            let fd = oracle::roots::central_difference(|q| x.eval(q), p, h);
            let err = (g - fd).length();
            assert!(
                err <= 1e-5 * (1.0 + g.length()) + 1e-6 * v.abs(),
                "{} at {p}: {g} vs {fd}",
                e.name
            );
        }
    }
}

// ---------------------------------------------------------------- roots

#[test]
fn root_with_zero_at_an_end() {
    let f = |p: DVec3| p.x;
    let (a, b) = (DVec3::ZERO, DVec3::new(-1.0, 0.0, 0.0));
    let tol = 1e-9;
    // f(a) = 0 counts as outside (f >= 0); the crossing is at a.
    for p in [
        roots::bisect(f, roots::Ends::new(a, 0.0, b, -1.0), tol),
        roots::try_find_root(f, roots::Ends::new(a, 0.0, b, -1.0), tol).unwrap(),
        roots::try_find_root(f, roots::Ends::new(b, -1.0, a, 0.0), tol).unwrap(),
    ] {
        assert!(p.distance(a) <= tol, "{p}");
    }
    // A plateau of zeros: the transition between f < 0 and f >= 0 is at x = -0.5, not at a zero
    // found first.
    let g = |p: DVec3| {
        if p.x < -0.5 {
            -2.0
        } else if p.x <= 0.0 {
            0.0
        } else {
            p.x
        }
    };
    let (a, b) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0));
    for p in [
        roots::bisect(g, roots::Ends::new(a, 1.0, b, -2.0), tol),
        roots::try_find_root(g, roots::Ends::new(a, 1.0, b, -2.0), tol).unwrap(),
    ] {
        assert!((p.x + 0.5).abs() <= tol, "{p}");
    }
}

#[test]
fn nan_is_reported_with_its_point() {
    let f = |p: DVec3| {
        if p.x > 0.2 && p.x < 0.3 {
            f64::NAN
        } else {
            p.x - 0.5
        }
    };
    let (a, b) = (DVec3::ZERO, DVec3::X);
    // Bisection probes 0.5 then 0.25: NaN.
    let e = roots::try_bisect(f, roots::Ends::new(a, f(a), b, f(b)), 1e-9).unwrap_err();
    assert_eq!(e, OracleError::NaN(0.25, 0.0, 0.0));
    assert!(roots::bisect(f, roots::Ends::new(a, f(a), b, f(b)), 1e-9).is_nan());
    let e =
        roots::try_find_root(|_| f64::NAN, roots::Ends::new(a, -1.0, b, 1.0), 1e-9).unwrap_err();
    assert!(matches!(e, OracleError::NaN(..)));
    assert!(roots::try_find_root(f, roots::Ends::new(a, f64::NAN, b, 1.0), 1e-9).is_err());
    let mut out = Vec::new();
    assert!(roots::try_all_crossings(f, a, b, 0.01, 1e-9, &mut out).is_err());
    // The default intersection oracle (`roots::all_crossings`) ends with a NaN point.
    struct NanBand;
    impl Surface for NanBand {
        fn bounding_sphere(&self) -> BoundingSphere {
            ball(10.0)
        }
        fn value(&self, p: DVec3) -> f64 {
            if p.x > 0.2 && p.x < 0.3 {
                f64::NAN
            } else {
                p.x - 0.5
            }
        }
    }
    out.clear();
    NanBand.crossings(a, b, &mut out);
    assert!(out.last().unwrap().is_nan());
    out.clear();
    roots::all_crossings(&NanBand, a, b, &mut out);
    assert!(out.last().unwrap().is_nan());
}

#[test]
fn safeguarded_method_is_faster_than_bisection_on_smooth_functions() {
    let mut rng = SplitMix64(5);
    let (mut n_illinois, mut n_bisect) = (0, 0);
    for _ in 0..200 {
        let a = DVec3::X;
        let b = a + rng.unit_vector() * 1.5;
        let count = Cell::new(0);
        let f = |p: DVec3| {
            count.set(count.get() + 1);
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            (x2 + y2 + z2 + 0.91).powi(2) - 4.0 * (x2 + y2) + 0.5 * p.z
        };
        let (fa, fb) = (f(a), f(b));
        if (fa < 0.0) == (fb < 0.0) {
            continue;
        }
        count.set(0);
        let p = roots::try_find_root(f, roots::Ends::new(a, fa, b, fb), 2e-7).unwrap();
        n_illinois += count.get();
        count.set(0);
        let q = roots::bisect(f, roots::Ends::new(a, fa, b, fb), 2e-7);
        n_bisect += count.get();
        assert!(p.distance(q) <= 2e-7, "{p} vs {q}");
    }
    assert!(n_bisect > 1000, "{n_bisect}");
    // Measured: about 11 evaluations per root against 22 (the function is far from linear at
    // the scale of the segment, so the first steps are slow).
    assert!(
        n_illinois * 10 < n_bisect * 6,
        "illinois {n_illinois} evaluations, bisection {n_bisect}"
    );
}

#[test]
fn sign_only_values_use_bisection() {
    let count = Cell::new(0);
    let f = |p: DVec3| {
        count.set(count.get() + 1);
        if p.x < 0.3 { -1.0 } else { 1.0 }
    };
    let (a, b) = (DVec3::ZERO, DVec3::X);
    let p = roots::try_find_root(f, roots::Ends::new(a, -1.0, b, 1.0), 1e-6).unwrap();
    assert!((p.x - 0.3).abs() <= 1e-6);
    assert!(count.get() <= 21, "{} evaluations", count.get());
    assert!(roots::is_sign_value(-1.0) && roots::is_sign_value(0.0) && !roots::is_sign_value(0.5));
}

// ---------------------------------------------------------------- ImplicitSurface

#[test]
fn crossings_along_the_torus_axis() {
    for s in [
        catalog::surface("torus").unwrap(),
        catalog::surface_from_expression("torus").unwrap(),
    ] {
        let mut out = Vec::new();
        s.crossings(
            DVec3::new(-2.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            &mut out,
        );
        assert_eq!(out.len(), 4, "{out:?}");
        for (p, want) in out.iter().zip([-1.3, -0.7, 0.7, 1.3]) {
            assert!((p.x - want).abs() <= s.tolerance(), "{p} vs {want}");
        }
    }
}

#[test]
fn bipolar_oracle_precision_on_the_sphere() {
    let s = ImplicitSurface::from_expr("x^2+y^2+z^2-1", ball(2.0)).unwrap();
    let mut rng = SplitMix64(3);
    for _ in 0..500 {
        let a = rng.unit_vector() * rng.next_f64() * 0.99;
        let b = rng.unit_vector() * (1.01 + rng.next_f64());
        let p = s.crossing(a, s.value(a), b, s.value(b));
        assert!(
            (p.length() - 1.0).abs() <= s.tolerance(),
            "{}",
            p.length() - 1.0
        );
        // and the point is on the segment
        assert!((p - a).cross(b - a).length() <= 1e-9 * (b - a).length());
    }
}

#[test]
fn sign_only_sphere() {
    let f = |p: DVec3| {
        let v = p.length_squared() - 1.0;
        if v < 0.0 {
            -1.0
        } else if v > 0.0 {
            1.0
        } else {
            0.0
        }
    };
    let surfaces = [
        ImplicitSurface::from_fn(f, ball(2.0)).unwrap(),
        ImplicitSurface::from_expr("sign(x^2+y^2+z^2-1)", ball(2.0)).unwrap(),
    ];
    for s in surfaces {
        assert!(s.is_sign_only());
        let mut rng = SplitMix64(9);
        for _ in 0..200 {
            let a = rng.unit_vector() * 0.5;
            let b = rng.unit_vector() * 1.8;
            let p = s.crossing(a, s.value(a), b, s.value(b));
            assert!((p.length() - 1.0).abs() <= s.tolerance());
        }
        let seeds = s.seed_points(4);
        assert!(seeds.len() >= 20);
        assert!(
            seeds
                .iter()
                .all(|p| (p.length() - 1.0).abs() <= s.tolerance())
        );
        let mut out = Vec::new();
        s.crossings(
            DVec3::new(-1.9, 0.1, 0.0),
            DVec3::new(1.9, 0.1, 0.0),
            &mut out,
        );
        assert_eq!(out.len(), 2);
    }
    assert!(!catalog::surface("sphere").unwrap().is_sign_only());
}

#[test]
fn bounding_sphere_errors() {
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = ImplicitSurface::from_expr("x^2+y^2+z^2-1", ball(r)).unwrap_err();
        assert!(matches!(e, ImplicitError::BadBoundingSphere { .. }), "{e}");
        assert!(e.to_string().contains("radius"));
    }
    let bad_center = BoundingSphere {
        center: DVec3::new(f64::NAN, 0.0, 0.0),
        radius: 2.0,
    };
    assert!(matches!(
        ImplicitSurface::from_expr("x^2+y^2+z^2-1", bad_center),
        Err(ImplicitError::BadBoundingSphere { .. })
    ));
    // The unit sphere crosses a ball of radius 0.9 ...
    let e = ImplicitSurface::from_expr("x^2+y^2+z^2-1", ball(0.9)).unwrap_err();
    let ImplicitError::CrossesBoundary { point, value, .. } = e else {
        panic!("{e}")
    };
    assert!((DVec3::from_array(point).length() - 0.9).abs() < 1e-12);
    assert!(value <= 0.0);
    // ... and a ball off-center; the message says what to do.
    let off = BoundingSphere {
        center: DVec3::new(1.5, 0.0, 0.0),
        radius: 1.0,
    };
    let e = ImplicitSurface::from_fn(|p: DVec3| p.length_squared() - 1.0, off).unwrap_err();
    assert!(
        e.to_string()
            .contains("enlarge the radius or move the center"),
        "{e}"
    );
    // Touching the sphere (f = 0 there) is also rejected.
    let e = ImplicitSurface::from_fn(
        |p: DVec3| (p.length_squared() - 4.0).min(p.length_squared() - 1.0),
        ball(2.0),
    );
    assert!(matches!(e, Err(ImplicitError::CrossesBoundary { .. })));
}

#[test]
fn nan_and_empty_inputs_are_errors() {
    // NaN inside a small interior ball: found on the grid.
    let f = |p: DVec3| {
        if p.length() < 0.3 {
            f64::NAN
        } else {
            p.length_squared() - 1.0
        }
    };
    let e = ImplicitSurface::from_fn(f, ball(2.0)).unwrap_err();
    let ImplicitError::NaN { point } = e else {
        panic!("{e}")
    };
    assert!(DVec3::from_array(point).length() < 0.3);
    assert!(e.to_string().contains("NaN"));
    // NaN on the bounding sphere.
    let e = ImplicitSurface::from_expr("sqrt(x)+y^2+z^2-1", ball(2.0)).unwrap_err();
    assert!(matches!(e, ImplicitError::NaN { .. }), "{e}");
    // Nothing inside.
    let e = ImplicitSurface::from_expr("x^2+y^2+z^2+1", ball(2.0)).unwrap_err();
    assert!(
        matches!(e, ImplicitError::NoSurfaceInside { n: 32, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("no surface inside"));
    // Parse errors come through with their column.
    let e = ImplicitSurface::from_expr("x^2+(y^2-1", ball(2.0)).unwrap_err();
    assert!(
        matches!(&e, ImplicitError::Expr(x) if x.column == 11),
        "{e}"
    );
    // Bad parameters.
    let b = |s| {
        ImplicitSurface::builder_from_expr("x^2+y^2+z^2-1", ball(2.0))
            .unwrap()
            .dm_inf_hint(s)
    };
    assert!(matches!(
        b(0.0).build(),
        Err(ImplicitError::BadParameter {
            name: "dm_inf_hint",
            ..
        })
    ));
    assert!(matches!(
        b(f64::NAN).build(),
        Err(ImplicitError::BadParameter { .. })
    ));
    assert_eq!(b(0.5).build().unwrap().dm_inf_hint(), Some(0.5));
    let e = ImplicitSurface::builder(|p: DVec3| p.length_squared() - 1.0, ball(2.0))
        .tolerance(-1.0)
        .build();
    assert!(matches!(
        e,
        Err(ImplicitError::BadParameter {
            name: "tolerance",
            ..
        })
    ));
    let e = ImplicitSurface::builder(|p: DVec3| p.length_squared() - 1.0, ball(2.0))
        .seed_points(vec![DVec3::splat(5.0)])
        .build();
    assert!(matches!(e, Err(ImplicitError::BadSeedPoint { .. })));
}

#[test]
fn tiny_component_needs_user_seeds() {
    // A sphere of radius 0.01: no grid vertex falls inside.
    let f = |p: DVec3| (p - DVec3::splat(0.33)).length_squared() - 1e-4;
    assert!(matches!(
        ImplicitSurface::from_fn(f, ball(2.0)),
        Err(ImplicitError::NoSurfaceInside { .. })
    ));
    let s = ImplicitSurface::builder(f, ball(2.0))
        .seed_points(vec![DVec3::splat(0.33) + DVec3::X * 0.01])
        .build()
        .unwrap();
    assert_eq!(s.seed_points(0)[0], DVec3::splat(0.33) + DVec3::X * 0.01);
}

#[test]
fn seeds_find_every_component_and_are_deterministic() {
    // Two disjoint spheres, one small.
    let c1 = DVec3::new(-0.8, 0.0, 0.0);
    let c2 = DVec3::new(1.0, 0.5, 0.3);
    let f = move |p: DVec3| ((p - c1).length() - 0.5).min((p - c2).length() - 0.2);
    let s = ImplicitSurface::from_fn(f, ball(2.0)).unwrap();
    let seeds = s.seed_points(1);
    assert!(seeds.len() <= 200 && seeds.len() >= 50, "{}", seeds.len());
    let on1 = seeds
        .iter()
        .filter(|p| ((**p - c1).length() - 0.5).abs() <= 1e-6)
        .count();
    let on2 = seeds
        .iter()
        .filter(|p| ((**p - c2).length() - 0.2).abs() <= 1e-6)
        .count();
    assert_eq!(on1 + on2, seeds.len());
    assert!(on1 >= 10 && on2 >= 3, "{on1} {on2}");
    // Distinct points.
    for (i, p) in seeds.iter().enumerate() {
        for q in &seeds[..i] {
            assert!(p.distance(*q) > 1e-7);
        }
    }
    // Deterministic: same seed, same points, whatever the thread count.
    for threads in [1, 3] {
        let again = common::with_threads(threads, || {
            ImplicitSurface::from_fn(f, ball(2.0))
                .unwrap()
                .seed_points(1)
        });
        assert_eq!(again, seeds, "{threads} threads");
    }
    assert_ne!(
        s.seed_points(2),
        seeds,
        "the random lines depend on the seed"
    );
}

#[test]
fn gradient_and_projection() {
    let s = ImplicitSurface::from_expr("x^2+y^2+z^2-1", ball(2.0)).unwrap();
    let p = DVec3::new(0.3, -0.2, 0.5);
    assert_eq!(s.gradient(p), 2.0 * p);
    let c = ImplicitSurface::from_fn(|p: DVec3| p.length_squared() - 1.0, ball(2.0)).unwrap();
    assert!((c.gradient(p) - 2.0 * p).length() < 1e-6);
    let q = s.project(DVec3::new(0.0, 1.3, 0.2)).unwrap();
    assert!((q.length() - 1.0).abs() < 1e-7);
}

/// A value function that is flat away from S (clamped to +-0.05: the unit sphere) stalls the
/// gradient steps; the projection then falls back to the nearest crossing on rays, a point
/// of S no closer to `p` than the true distance and not much farther.
#[test]
fn projection_falls_back_to_rays_where_the_value_is_flat() {
    let s = ImplicitSurface::from_fn(|p: DVec3| (p.length() - 1.0).clamp(-0.05, 0.05), ball(3.0))
        .unwrap();
    let mut rng = SplitMix64(17);
    for _ in 0..40 {
        let dir = rng.unit_vector();
        for r in [0.3, 0.6, 1.6, 2.5] {
            let p = dir * r;
            assert!(roots::project_newton(&s, p).is_none(), "flat at {p}");
            let q = s.project(p).expect("rays meet the sphere");
            assert!((q.length() - 1.0).abs() < 1e-6, "{q} is not on S");
            let d = (r - 1.0f64).abs();
            let got = (q - p).length();
            assert!(
                got >= d - 1e-6 && got <= 1.02 * d + 1e-3,
                "r {r}: {got} vs {d}"
            );
        }
    }
    // A NaN region on some rays: the crossings there are skipped, the others still count.
    struct NanBeyond;
    impl Surface for NanBeyond {
        fn bounding_sphere(&self) -> BoundingSphere {
            BoundingSphere::at_origin(3.0)
        }
        fn value(&self, p: DVec3) -> f64 {
            if p.x > 1.5 {
                f64::NAN
            } else {
                (p.length() - 1.0).clamp(-0.05, 0.05)
            }
        }
    }
    let q = NanBeyond.project(DVec3::new(1.3, 0.0, 0.0)).unwrap();
    assert!(q.is_finite() && (q - DVec3::X).length() < 0.01, "{q}");
    // Far outside the bounding sphere: the rays are clipped to it, so this stays cheap, and
    // the point found is on S.
    let q = s.project(DVec3::new(1e3, 0.0, 0.0)).unwrap();
    assert!((q.length() - 1.0).abs() < 1e-6 && q.x > 0.99, "{q}");
}

// ---------------------------------------------------------------- catalog

#[test]
fn catalog_names_and_entries() {
    let names = catalog::names();
    assert_eq!(
        names,
        [
            "sphere",
            "ellipsoid",
            "torus",
            "double_torus",
            "tanglecube",
            "chair",
            "blobs",
            "heart",
            "trefoil",
            "barth_octic",
            "klein_bottle"
        ]
    );
    let genus: Vec<Option<u32>> = names[..8]
        .iter()
        .map(|n| catalog::entry(n).unwrap().genus)
        .collect();
    assert_eq!(genus, [0, 0, 1, 2, 5, 3, 0, 0].map(Some));
    assert_eq!(catalog::entry("sphere").unwrap().dm_inf, Some(1.0));
    assert_eq!(catalog::entry("torus").unwrap().dm_inf, Some(0.3));
    assert_eq!(catalog::entry("ellipsoid").unwrap().dm_inf, Some(0.16));
    assert_eq!(catalog::entry("chair").unwrap().dm_inf, None);
    assert!(!catalog::entry("heart").unwrap().smooth);
    assert!(!catalog::entry("barth_octic").unwrap().smooth);
    assert!(!catalog::entry("klein_bottle").unwrap().smooth);
    assert_eq!(catalog::entry("trefoil").unwrap().genus, Some(1));
    assert_eq!(
        catalog::entry("double_torus")
            .unwrap()
            .bounding_sphere
            .center,
        DVec3::X
    );
    let e = catalog::surface("teapot").unwrap_err();
    assert!(
        e.to_string().contains("unknown catalog surface 'teapot'")
            && e.to_string().contains("tanglecube")
    );
    assert!(catalog::entry("teapot").is_none());
}

#[test]
fn native_closures_equal_compiled_expressions() {
    let mut rng = SplitMix64(2024);
    for e in catalog::entries() {
        let native = catalog::native_fn(e.name).unwrap();
        let Some(src) = &e.expression else {
            continue;
        };
        let x = Expr::parse(src).unwrap();
        let bs = e.bounding_sphere;
        let pts: Vec<DVec3> = (0..5000)
            .map(|_| bs.center + rng.unit_vector() * bs.radius * rng.next_f64().cbrt() * 1.2)
            .collect();
        let scale = pts.iter().map(|p| x.eval(*p).abs()).fold(1.0, f64::max);
        for p in pts {
            let (a, b) = (native(p), x.eval(p));
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "{} at {p}: native {a}, compiled {b}",
                e.name
            );
        }
    }
}

#[test]
fn catalog_functions_are_positive_on_their_bounding_spheres() {
    for e in catalog::entries() {
        let f = catalog::native_fn(e.name).unwrap();
        for u in fibonacci_sphere(20_000) {
            let p = e.bounding_sphere.center + u * e.bounding_sphere.radius;
            assert!(f(p) > 0.0, "{} at {p}", e.name);
        }
    }
}

#[test]
fn catalog_seeds_are_on_the_surfaces() {
    for name in catalog::names() {
        let s = catalog::surface(name).unwrap_or_else(|e| panic!("{e}"));
        let seeds = s.seed_points(0);
        assert!(seeds.len() >= 50, "{name}: {} seeds", seeds.len());
        for p in &seeds {
            let (v, g) = (s.value(*p), s.gradient(*p).length());
            assert!(
                v.abs() <= s.tolerance() * g + 1e-12,
                "{name}: f({p}) = {v}, |grad| = {g}"
            );
            assert!(s.bounding_sphere().contains(*p));
        }
        // The expression path builds too (except for native-only surfaces).
        match catalog::surface_from_expression(name) {
            Ok(x) => assert_eq!(x.is_sign_only(), s.is_sign_only()),
            Err(e) => {
                assert!(catalog::entry(name).unwrap().expression.is_none());
                assert!(e.to_string().contains("no closed-form expression"), "{e}");
            }
        }
    }
}

#[test]
fn user_seeds_are_kept_under_the_cap() {
    let user = vec![DVec3::X, DVec3::Y, DVec3::Z];
    let s = ImplicitSurface::builder(|p: DVec3| p.length_squared() - 1.0, ball(2.0))
        .seed_points(user.clone())
        .max_seeds(5)
        .build()
        .unwrap();
    let seeds = s.seed_points(0);
    assert_eq!(seeds.len(), 5);
    assert_eq!(&seeds[..3], &user[..]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random spheres in random bounding spheres: accepted when inside (seeds and crossings on
    /// them), rejected with `CrossesBoundary` when they stick out.
    #[test]
    fn random_spheres(c in prop::array::uniform3(-1.0f64..1.0), r in 0.2f64..1.0,
                      bc in prop::array::uniform3(-1.0f64..1.0), br in 0.5f64..4.0, seed in any::<u64>()) {
        let (c, bc) = (DVec3::from_array(c), DVec3::from_array(bc));
        let bs = BoundingSphere { center: bc, radius: br };
        let f = move |p: DVec3| (p - c).length() - r;
        let far = (c - bc).length() + r; // farthest point of the sphere from bc
        let res = ImplicitSurface::from_fn(f, bs);
        if far < br * 0.99 {
            let s = res.map_err(|e| TestCaseError::fail(e.to_string()))?;
            let seeds = s.seed_points(seed);
            prop_assert!(!seeds.is_empty());
            for p in &seeds {
                prop_assert!(((*p - c).length() - r).abs() <= s.tolerance());
            }
            let mut rng = SplitMix64(seed);
            let a = c + rng.unit_vector() * r * 0.5;
            let b = c + rng.unit_vector() * r * 1.5;
            if bs.contains(b) {
                let p = s.crossing(a, s.value(a), b, s.value(b));
                prop_assert!(((p - c).length() - r).abs() <= s.tolerance());
            }
        } else if (c - bc).length() + r > br * 1.05 && (c - bc).length() - r < br * 0.95 {
            // The sphere crosses the bounding sphere well away from tangency.
            let crosses = matches!(res, Err(ImplicitError::CrossesBoundary { .. }));
            prop_assert!(crosses);
        }
    }
}

#[test]
fn resolve_specs_and_bounding_sphere_syntax() {
    use oracle::catalog::CatalogError;
    use oracle::implicit::parse_bounding_sphere;
    let bs = parse_bounding_sphere("0,0,0,3").unwrap();
    assert_eq!(bs, ball(3.0));
    for bad in [
        "",
        "1,2,3",
        "1,2,3,4,5",
        "0,0,zero,1",
        "0,0,0,inf",
        "0,0,0,NaN",
    ] {
        let e = parse_bounding_sphere(bad).unwrap_err();
        assert!(e.to_string().contains("cx,cy,cz,r"), "{e}");
    }
    // Catalog name, default and overridden bounding sphere.
    assert_eq!(
        catalog::resolve("chair", None)
            .unwrap()
            .bounding_sphere()
            .radius,
        7.0
    );
    let t = catalog::resolve(" torus ", Some(ball(3.0))).unwrap();
    assert_eq!(t.bounding_sphere().radius, 3.0);
    assert_eq!(t.dm_inf_hint(), Some(0.3));
    assert!(matches!(
        catalog::resolve("torus", Some(ball(1.0))),
        Err(CatalogError::Implicit { .. })
    ));
    // Expressions.
    let s = catalog::resolve("x^2+y^2+z^2-1", Some(ball(2.0))).unwrap();
    assert!(s.expr().is_some());
    assert!(matches!(
        catalog::resolve("x^2+y^2+z^2-1", None),
        Err(CatalogError::MissingBoundingSphere { .. })
    ));
    let e = catalog::resolve("x^2+(y^2-1", Some(ball(2.0))).unwrap_err();
    assert!(e.to_string().contains("at column 11"), "{e}");
    let e = catalog::resolve("spere", Some(ball(2.0))).unwrap_err();
    assert!(matches!(e, CatalogError::UnknownName { .. }), "{e}");
}

#[test]
fn seeds_stay_inside_the_ball_when_the_surface_comes_close() {
    // f < 0 again just outside the ball: seeds must come from the
    // inner sphere only, which nearly touches the bounding sphere.
    let f = |p: DVec3| {
        let r = p.length();
        if r <= 2.0 { r - 1.97 } else { 2.0 + 1e-9 - r }
    };
    let s = ImplicitSurface::from_fn(f, ball(2.0)).unwrap();
    let seeds = s.seed_points(3);
    assert!(seeds.len() >= 100);
    for p in seeds {
        assert!((p.length() - 1.97).abs() <= s.tolerance(), "{}", p.length());
    }
}

/// Euler characteristic of the union of the closed voxels (step `h`, over the box `lo..hi`)
/// whose centers have f < 0.
fn voxel_euler(f: fn(DVec3) -> f64, lo: DVec3, hi: DVec3, h: f64) -> i64 {
    use rayon::prelude::*;
    let n = ((hi - lo) / h).ceil().as_uvec3();
    let (nx, ny, nz) = (n.x as usize, n.y as usize, n.z as usize);
    let inside: Vec<bool> = (0..nx * ny * nz)
        .into_par_iter()
        .map(|i| {
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            f(lo + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * h) < 0.0
        })
        .collect();
    let vox = |x: i64, y: i64, z: i64| {
        x >= 0
            && y >= 0
            && z >= 0
            && (x as usize) < nx
            && (y as usize) < ny
            && (z as usize) < nz
            && inside[x as usize + nx * (y as usize + ny * z as usize)]
    };
    // Lattice point (x, y, z) is the corner shared by voxels (x-1..x, y-1..y, z-1..z). A cell of
    // the cubical complex is present if one of the voxels around it is.
    let mut chi = 0i64;
    for z in 0..=nz as i64 {
        for y in 0..=ny as i64 {
            for x in 0..=nx as i64 {
                let any = |dx: &[i64], dy: &[i64], dz: &[i64]| {
                    dx.iter().any(|&a| {
                        dy.iter()
                            .any(|&b| dz.iter().any(|&c| vox(x + a, y + b, z + c)))
                    })
                };
                let (both, zero) = (&[-1, 0][..], &[0][..]);
                chi += any(both, both, both) as i64; // vertex
                chi -= any(zero, both, both) as i64
                    + any(both, zero, both) as i64
                    + any(both, both, zero) as i64; // edges along x, y, z
                chi += any(zero, zero, both) as i64
                    + any(zero, both, zero) as i64
                    + any(both, zero, zero) as i64; // faces
                chi -= vox(x, y, z) as i64; // cube
            }
        }
    }
    chi
}

/// The catalog's genus and component counts agree with the topology of the solid f < 0:
/// a solid bounded by c closed surfaces of genus g_i has Euler characteristic sum(1 - g_i).
#[test]
fn catalog_topology_matches_voxel_euler_characteristic() {
    for e in catalog::entries() {
        let (Some(g), Some(c)) = (e.genus, e.components) else {
            continue;
        };
        let f = catalog::native_fn(e.name).unwrap();
        let bs = e.bounding_sphere;
        let h = bs.radius / 64.0;
        let lo = bs.center - DVec3::splat(bs.radius);
        let hi = bs.center + DVec3::splat(bs.radius);
        let chi = voxel_euler(f, lo, hi, h);
        assert_eq!(
            chi,
            c as i64 - g as i64,
            "{}: chi = {chi}, genus {g}, {c} component(s)",
            e.name
        );
    }
}

/// The trefoil is the tube of radius 0.2 around its curve: where the distance to the curve
/// (checked against a brute-force minimum over 200 000 curve points, refined) is below 0.33,
/// the native value is that distance minus 0.2, elsewhere it is at least 0.13; its gradient is
/// a unit vector equal to finite differences, and d_M^inf is 0.2.
#[test]
fn trefoil_is_a_tube_of_constant_radius() {
    use catalog::{TREFOIL_TUBE, trefoil_curve};
    let n = 200_000;
    let h = std::f64::consts::TAU / n as f64;
    let curve: Vec<DVec3> = (0..n).map(|k| trefoil_curve(k as f64 * h).0).collect();
    let brute = |p: DVec3| {
        let (k, _) = curve
            .iter()
            .enumerate()
            .map(|(k, q)| (k, q.distance_squared(p)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        // Golden-section refinement on [t_k - h, t_k + h].
        let d = |t: f64| trefoil_curve(t).0.distance(p);
        let (mut a, mut b) = (k as f64 * h - h, k as f64 * h + h);
        for _ in 0..80 {
            let (m1, m2) = (a + 0.382 * (b - a), a + 0.618 * (b - a));
            if d(m1) < d(m2) { b = m2 } else { a = m1 }
        }
        d(0.5 * (a + b))
    };
    let s = catalog::surface("trefoil").unwrap();
    assert_eq!(s.dm_inf_hint(), Some(TREFOIL_TUBE));
    let f = catalog::native_fn("trefoil").unwrap();
    let mut rng = SplitMix64(7);
    let mut near = 0;
    for i in 0..400 {
        // Half the points near the tube (around a random curve point), half anywhere.
        let p = if i % 2 == 0 {
            let t = rng.next_f64() * std::f64::consts::TAU;
            trefoil_curve(t).0 + rng.unit_vector() * 0.35 * rng.next_f64()
        } else {
            rng.unit_vector() * 2.0 * rng.next_f64().cbrt()
        };
        let (v, b) = (f(p), brute(p) - TREFOIL_TUBE);
        if b < 0.13 {
            near += 1;
            assert!((v - b).abs() < 1e-9, "at {p}: native {v}, brute force {b}");
        } else {
            assert!(
                b > 0.0 && v >= 0.13 - 1e-9,
                "at {p}: native {v}, brute force {b}"
            );
        }
        let g = s.gradient(p);
        assert!((g.length() - 1.0).abs() < 1e-9, "|grad| at {p}");
        let e = 1e-6;
        let fd = oracle::roots::central_difference(f, p, e);
        if b.abs() < 0.13 {
            assert!((g - fd).length() < 1e-5, "grad at {p}: {g} vs {fd}");
        }
    }
    assert!(near > 150, "{near} points near the tube");
    let e = catalog::surface_from_expression("trefoil").unwrap_err();
    assert!(matches!(e, catalog::CatalogError::NoExpression { .. }));
}
