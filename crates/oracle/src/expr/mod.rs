//! Expressions in `x`, `y`, `z` (ours, for section 6.6.1's implicit surfaces): a parser with column-accurate errors and a compiler to a flat
//! SSA register program, evaluated without re-parsing.
//!
//! Grammar (usual precedence, `^` right-associative and binding tighter than unary minus, so
//! `-x^2 = -(x^2)` and `2^3^2 = 2^9`):
//!
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary)*
//! unary   := ('-' | '+') unary | power
//! power   := primary (('^' | '**') unary)?
//! primary := number | 'x' | 'y' | 'z' | 'pi' | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//!
//! Numbers: `2`, `0.5`, `.5`, `1e-3`, `2.5E+2`. Functions: `sqrt`, `cbrt`, `exp`, `ln` (= `log`,
//! natural), `sin`, `cos`, `tan`, `atan`, `abs`, `sign` (-1, 0 or 1), `min(a,b)`, `max(a,b)`,
//! `pow(a,b)` (= `a^b`).
//!
//! Compilation ([`Expr::parse`]) folds constants, shares common subexpressions, turns constant
//! integer powers into multiplications (`x^4` is two multiplications, shared with `x^2`), and
//! `a^0.5` into `sqrt(a)`. A non-integer power of a negative number is NaN (as `f64::powf`).
//! [`Expr::eval_grad`] gives the exact gradient by forward-mode differentiation of the program.
//!
//! ```
//! use oracle::expr::Expr;
//! use glam::DVec3;
//! let e = Expr::parse("x^2 + y^2 + z^2 - 1").unwrap();
//! assert_eq!(e.eval(DVec3::new(1.0, 1.0, 0.0)), 1.0);
//! let err = Expr::parse("x^2+(y^2-1").unwrap_err();
//! assert_eq!(err.column, 11);
//! assert!(err.to_string().starts_with("expected ')', found end of input at column 11"));
//! ```

mod compile;
mod dual;
mod error;
mod eval;
mod lexer;
mod parser;

pub use error::{ExprError, ExprErrorKind};

use compile::{Ins, compile};
use dual::dual;
use eval::apply;
use glam::DVec3;
use parser::{Ast, parse_ast};
use std::fmt;

/// A compiled expression in `x`, `y`, `z`: a flat program of SSA instructions over a register
/// file (variables, constants, temporaries). `Send + Sync`; [`Expr::eval`] never allocates for
/// programs of up to 256 registers.
#[derive(Clone, Debug)]
pub struct Expr {
    source: String,
    ast: Ast,
    /// Register file template: x, y, z, constants; temps follow.
    init: Vec<f64>,
    code: Vec<Ins>,
    result: u32,
}

impl Expr {
    /// Parse and compile `src`. Errors carry the column (see [`ExprError`]).
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let ast = parse_ast(src)?;
        let (init, code, result) = compile(&ast);
        Ok(Expr {
            source: src.to_string(),
            ast,
            init,
            code,
            result,
        })
    }

    /// The source text.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Number of instructions of the compiled program (after folding and sharing).
    pub fn instruction_count(&self) -> usize {
        self.code.len()
    }

    fn nregs(&self) -> usize {
        self.init.len() + self.code.len()
    }

    #[inline]
    fn run(&self, regs: &mut [f64], p: DVec3) -> f64 {
        let n0 = self.init.len();
        regs[..n0].copy_from_slice(&self.init);
        regs[0] = p.x;
        regs[1] = p.y;
        regs[2] = p.z;
        for (k, ins) in self.code.iter().enumerate() {
            let a = regs[ins.a as usize];
            let b = regs[ins.b as usize];
            regs[n0 + k] = apply(ins.op, a, b);
        }
        regs[self.result as usize]
    }

    /// Value at `p`.
    #[inline]
    pub fn eval(&self, p: DVec3) -> f64 {
        let n = self.nregs();
        if n <= 64 {
            let mut regs = [0.0; 64];
            self.run(&mut regs[..n], p)
        } else if n <= 256 {
            let mut regs = [0.0; 256];
            self.run(&mut regs[..n], p)
        } else {
            let mut regs = vec![0.0; n];
            self.run(&mut regs, p)
        }
    }

    /// Value and exact gradient at `p` (forward-mode differentiation of the program). At kinks
    /// (`abs`, `min`, `max`, `sign`) one one-sided derivative is returned.
    pub fn eval_grad(&self, p: DVec3) -> (f64, DVec3) {
        let n = self.nregs();
        if n <= 64 {
            let mut regs = [[0.0; 4]; 64];
            self.run_dual(&mut regs[..n], p)
        } else if n <= 256 {
            let mut regs = [[0.0; 4]; 256];
            self.run_dual(&mut regs[..n], p)
        } else {
            let mut regs = vec![[0.0; 4]; n];
            self.run_dual(&mut regs, p)
        }
    }

    fn run_dual(&self, regs: &mut [[f64; 4]], p: DVec3) -> (f64, DVec3) {
        let n0 = self.init.len();
        regs[0] = [p.x, 1.0, 0.0, 0.0];
        regs[1] = [p.y, 0.0, 1.0, 0.0];
        regs[2] = [p.z, 0.0, 0.0, 1.0];
        for (r, &c) in regs[3..n0].iter_mut().zip(&self.init[3..]) {
            *r = [c, 0.0, 0.0, 0.0];
        }
        for (k, ins) in self.code.iter().enumerate() {
            let a = regs[ins.a as usize];
            let b = regs[ins.b as usize];
            regs[n0 + k] = dual(ins.op, a, b);
        }
        let r = regs[self.result as usize];
        (r[0], DVec3::new(r[1], r[2], r[3]))
    }

    /// Slow reference interpreter of the syntax tree (no folding, `powf` for every power); for
    /// tests of the compiler.
    pub fn eval_tree(&self, p: DVec3) -> f64 {
        self.ast.eval(p.to_array())
    }
}

impl std::str::FromStr for Expr {
    type Err = ExprError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Expr::parse(s)
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source)
    }
}
