//! Derivatives of expressions (ours): forward-mode differentiation of one instruction on
//! dual numbers `[value, d/dx, d/dy, d/dz]`.

use super::eval::{Op, sign};

pub(super) fn dual(op: Op, a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let map = |v: f64, k: f64, d: [f64; 4]| [v, k * d[1], k * d[2], k * d[3]];
    match op {
        Op::Add => [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]],
        Op::Sub => [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]],
        Op::Mul => [
            a[0] * b[0],
            a[1] * b[0] + a[0] * b[1],
            a[2] * b[0] + a[0] * b[2],
            a[3] * b[0] + a[0] * b[3],
        ],
        Op::Div => {
            let q = a[0] / b[0];
            [
                q,
                (a[1] - q * b[1]) / b[0],
                (a[2] - q * b[2]) / b[0],
                (a[3] - q * b[3]) / b[0],
            ]
        }
        Op::Neg => [-a[0], -a[1], -a[2], -a[3]],
        Op::Powf => {
            let v = a[0].powf(b[0]);
            let ka = b[0] * a[0].powf(b[0] - 1.0);
            let mut r = map(v, ka, a);
            if b[1] != 0.0 || b[2] != 0.0 || b[3] != 0.0 {
                let kb = v * a[0].ln();
                for i in 1..4 {
                    r[i] += kb * b[i];
                }
            }
            r
        }
        Op::Sqrt => {
            let s = a[0].sqrt();
            map(s, 0.5 / s, a)
        }
        Op::Cbrt => {
            let c = a[0].cbrt();
            map(c, 1.0 / (3.0 * c * c), a)
        }
        Op::Exp => {
            let e = a[0].exp();
            map(e, e, a)
        }
        Op::Ln => map(a[0].ln(), 1.0 / a[0], a),
        Op::Sin => map(a[0].sin(), a[0].cos(), a),
        Op::Cos => map(a[0].cos(), -a[0].sin(), a),
        Op::Tan => {
            let t = a[0].tan();
            map(t, 1.0 + t * t, a)
        }
        Op::Atan => map(a[0].atan(), 1.0 / (1.0 + a[0] * a[0]), a),
        Op::Abs => map(a[0].abs(), if a[0] < 0.0 { -1.0 } else { 1.0 }, a),
        Op::Sign => [sign(a[0]), 0.0, 0.0, 0.0],
        Op::Min => {
            if a[0] <= b[0] || b[0].is_nan() {
                a
            } else {
                b
            }
        }
        Op::Max => {
            if a[0] >= b[0] || b[0].is_nan() {
                a
            } else {
                b
            }
        }
    }
}
