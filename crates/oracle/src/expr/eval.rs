//! Evaluation of expressions (ours): the instruction set of the register program (also the
//! functions of the syntax tree) and its arithmetic.

/// Instruction codes of the register program.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Neg,
    Powf,
    Sqrt,
    Cbrt,
    Exp,
    Ln,
    Sin,
    Cos,
    Tan,
    Atan,
    Abs,
    Sign,
    Min,
    Max,
}

pub(super) fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        a // 0, -0 or NaN
    }
}

#[inline(always)]
pub(super) fn apply(op: Op, a: f64, b: f64) -> f64 {
    match op {
        Op::Add => a + b,
        Op::Sub => a - b,
        Op::Mul => a * b,
        Op::Div => a / b,
        Op::Neg => -a,
        Op::Powf => a.powf(b),
        Op::Sqrt => a.sqrt(),
        Op::Cbrt => a.cbrt(),
        Op::Exp => a.exp(),
        Op::Ln => a.ln(),
        Op::Sin => a.sin(),
        Op::Cos => a.cos(),
        Op::Tan => a.tan(),
        Op::Atan => a.atan(),
        Op::Abs => a.abs(),
        Op::Sign => sign(a),
        Op::Min => a.min(b),
        Op::Max => a.max(b),
    }
}
