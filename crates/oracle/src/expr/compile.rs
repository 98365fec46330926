//! Compilation of expressions (ours) to a flat SSA register program: constant folding,
//! common-subexpression sharing, integer powers as multiplications.

use super::eval::{Op, apply};
use super::parser::Ast;
use std::collections::HashMap;

/// One SSA instruction: `reg[first_temp + k] = op(reg[a], reg[b])`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Ins {
    pub op: Op,
    pub a: u32,
    pub b: u32,
}

/// SSA builder with constant folding and common-subexpression sharing.
struct Builder {
    consts: Vec<f64>,
    const_ids: HashMap<u64, u32>,
    // Instructions refer to registers: 0..3 variables, 3..3+MAXC constants (offset later),
    // temps after. During building we use tagged ids: Var(i), Const(i), Temp(i).
    code: Vec<(Op, Reg, Reg)>,
    memo: HashMap<(Op, Reg, Reg), Reg>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Reg {
    Var(u8),
    Const(u32),
    Temp(u32),
}

impl Builder {
    fn constant(&mut self, v: f64) -> Reg {
        let key = v.to_bits();
        if let Some(&i) = self.const_ids.get(&key) {
            return Reg::Const(i);
        }
        let i = self.consts.len() as u32;
        self.consts.push(v);
        self.const_ids.insert(key, i);
        Reg::Const(i)
    }
    fn const_value(&self, r: Reg) -> Option<f64> {
        match r {
            Reg::Const(i) => Some(self.consts[i as usize]),
            _ => None,
        }
    }
    fn emit(&mut self, op: Op, a: Reg, b: Reg) -> Reg {
        // Constant folding.
        let unary = !matches!(
            op,
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Powf | Op::Min | Op::Max
        );
        let b = if unary { a } else { b };
        if let (Some(x), Some(y)) = (self.const_value(a), self.const_value(b)) {
            return self.constant(apply(op, x, y));
        }
        // Exact algebraic identities only (they hold for every f64, NaN and infinities too).
        match (op, self.const_value(a), self.const_value(b)) {
            (Op::Add, _, Some(z)) | (Op::Sub, _, Some(z))
                if z == 0.0 && z.is_sign_negative() == (op == Op::Add) =>
            {
                return a;
            }
            (Op::Mul, _, Some(1.0)) | (Op::Div, _, Some(1.0)) => return a,
            (Op::Mul, Some(1.0), _) => return b,
            _ => {}
        }
        // Commutative ops: canonical operand order improves sharing.
        let (a, b) = if matches!(op, Op::Add | Op::Mul) && b < a {
            (b, a)
        } else {
            (a, b)
        };
        if let Some(&r) = self.memo.get(&(op, a, b)) {
            return r;
        }
        let r = Reg::Temp(self.code.len() as u32);
        self.code.push((op, a, b));
        self.memo.insert((op, a, b), r);
        r
    }
    fn powi(&mut self, a: Reg, n: u32) -> Reg {
        match n {
            0 => self.constant(1.0),
            1 => a,
            _ => {
                let h = self.powi(a, n / 2);
                let sq = self.emit(Op::Mul, h, h);
                if n % 2 == 1 {
                    self.emit(Op::Mul, sq, a)
                } else {
                    sq
                }
            }
        }
    }
    fn lower(&mut self, e: &Ast) -> Reg {
        match e {
            Ast::Num(v) => self.constant(*v),
            Ast::Var(i) => Reg::Var(*i),
            Ast::Neg(x) => {
                let x = self.lower(x);
                self.emit(Op::Neg, x, x)
            }
            Ast::Bin(op, l, r) => {
                let l = self.lower(l);
                let r = self.lower(r);
                match op {
                    '+' => self.emit(Op::Add, l, r),
                    '-' => self.emit(Op::Sub, l, r),
                    '*' => self.emit(Op::Mul, l, r),
                    '/' => self.emit(Op::Div, l, r),
                    _ => self.pow(l, r),
                }
            }
            Ast::Call(f, args) => {
                let a = self.lower(&args[0]);
                let b = if args.len() > 1 {
                    self.lower(&args[1])
                } else {
                    a
                };
                if *f == Op::Powf {
                    self.pow(a, b)
                } else {
                    self.emit(*f, a, b)
                }
            }
        }
    }
    fn pow(&mut self, a: Reg, b: Reg) -> Reg {
        if let Some(n) = self.const_value(b) {
            if n.fract() == 0.0 && n.abs() <= 64.0 && self.const_value(a).is_none() {
                let p = self.powi(a, n.abs() as u32);
                if n < 0.0 {
                    let one = self.constant(1.0);
                    return self.emit(Op::Div, one, p);
                }
                return p;
            }
            if n == 0.5 {
                return self.emit(Op::Sqrt, a, a);
            }
        }
        self.emit(Op::Powf, a, b)
    }
}

/// Compile a syntax tree to a register program: the register file template (x, y, z, then
/// the constants; temporaries follow), the instructions and the result register.
pub(super) fn compile(ast: &Ast) -> (Vec<f64>, Vec<Ins>, u32) {
    let mut b = Builder {
        consts: Vec::new(),
        const_ids: HashMap::new(),
        code: Vec::new(),
        memo: HashMap::new(),
    };
    let out = b.lower(ast);
    let nconst = b.consts.len() as u32;
    let base = 3 + nconst;
    let reg = |r: Reg| match r {
        Reg::Var(i) => i as u32,
        Reg::Const(i) => 3 + i,
        Reg::Temp(i) => base + i,
    };
    let code = b
        .code
        .iter()
        .map(|&(op, a, bb)| Ins {
            op,
            a: reg(a),
            b: reg(bb),
        })
        .collect();
    let mut init = vec![0.0; 3];
    init.extend_from_slice(&b.consts);
    (init, code, reg(out))
}
