//! Evaluation of expressions (ours): the instruction set of the register program and the
//! reference interpreter of the syntax tree.

use super::parser::{Ast, Func};

pub(super) fn eval_ast(a: &Ast, p: [f64; 3]) -> f64 {
    match a {
        Ast::Num(v) => *v,
        Ast::Var(i) => p[*i as usize],
        Ast::Neg(e) => -eval_ast(e, p),
        Ast::Bin(op, l, r) => {
            let (l, r) = (eval_ast(l, p), eval_ast(r, p));
            match op {
                '+' => l + r,
                '-' => l - r,
                '*' => l * r,
                '/' => l / r,
                _ => l.powf(r),
            }
        }
        Ast::Call(f, args) => {
            let a = eval_ast(&args[0], p);
            let b = args.get(1).map_or(0.0, |e| eval_ast(e, p));
            apply(func_op(*f), a, b)
        }
    }
}

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

pub(super) fn func_op(f: Func) -> Op {
    match f {
        Func::Sqrt => Op::Sqrt,
        Func::Cbrt => Op::Cbrt,
        Func::Exp => Op::Exp,
        Func::Ln => Op::Ln,
        Func::Sin => Op::Sin,
        Func::Cos => Op::Cos,
        Func::Tan => Op::Tan,
        Func::Atan => Op::Atan,
        Func::Abs => Op::Abs,
        Func::Sign => Op::Sign,
        Func::Min => Op::Min,
        Func::Max => Op::Max,
        Func::Pow => Op::Powf,
    }
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
