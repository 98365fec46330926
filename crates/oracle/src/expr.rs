//! Expressions in `x`, `y`, `z`: a parser with column-accurate errors and a compiler to a flat
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

use glam::DVec3;
use std::collections::HashMap;
use std::fmt;

/// What went wrong in an expression (see [`ExprError`] for the position).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExprErrorKind {
    #[error("expected {expected}, found {found}")]
    Expected { expected: String, found: String },
    #[error("unexpected character '{0}'")]
    UnexpectedChar(char),
    #[error("invalid number '{0}'")]
    InvalidNumber(String),
    #[error("unknown variable '{0}' (expressions use x, y, z and the constant pi)")]
    UnknownVariable(String),
    #[error(
        "unknown function '{0}' (known: sqrt, cbrt, exp, ln, log, sin, cos, tan, atan, abs, sign, min, max, pow)"
    )]
    UnknownFunction(String),
    #[error("function '{name}' takes {expected} argument(s), found {found}")]
    Arity {
        name: String,
        expected: usize,
        found: usize,
    },
    #[error("'{0}' is not a function; write '{0}*(...)' for a product")]
    NotAFunction(String),
    #[error("empty expression")]
    Empty,
    #[error("expression nested deeper than {MAX_DEPTH} levels")]
    TooDeep,
}

/// A parse error: its kind, the 1-based column (in characters) where it was detected, and the
/// input. Displays on one line as `KIND at column N: INPUT` with `>>` marking the column,
/// e.g. `unexpected '*' at column 9: x^2+y^2+>>*z^2-1`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{kind} at column {column}: {caret}")]
pub struct ExprError {
    pub kind: ExprErrorKind,
    /// 1-based column; `input.chars().count() + 1` for "end of input".
    pub column: usize,
    pub input: String,
    caret: String,
}

impl ExprError {
    fn new(kind: ExprErrorKind, column: usize, input: &str) -> Self {
        let before: String = input.chars().take(column.saturating_sub(1)).collect();
        let after: String = input.chars().skip(column.saturating_sub(1)).collect();
        let caret = format!("{before}>>{after}");
        ExprError {
            kind,
            column,
            input: input.to_string(),
            caret,
        }
    }
}

/// Nesting limit (parentheses, unary operators, function calls): deeper input is an error, not
/// a stack overflow.
const MAX_DEPTH: usize = 256;

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Sym(char),
    End,
}

impl fmt::Display for Tok {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tok::Num(v) => write!(f, "number {v}"),
            Tok::Ident(s) => write!(f, "'{s}'"),
            Tok::Sym(c) => write!(f, "'{c}'"),
            Tok::End => write!(f, "end of input"),
        }
    }
}

fn tokenize(src: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                } else {
                    let bad: String = chars[start..j.min(chars.len())].iter().collect();
                    return Err(ExprError::new(ExprErrorKind::InvalidNumber(bad), col, src));
                }
            }
            let text: String = chars[start..i].iter().collect();
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => out.push((Tok::Num(v), col)),
                _ => return Err(ExprError::new(ExprErrorKind::InvalidNumber(text), col, src)),
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(chars[start..i].iter().collect()), col));
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            out.push((Tok::Sym('^'), col));
            i += 2;
        } else if "+-*/^(),".contains(c) {
            out.push((Tok::Sym(c), col));
            i += 1;
        } else {
            return Err(ExprError::new(ExprErrorKind::UnexpectedChar(c), col, src));
        }
    }
    out.push((Tok::End, chars.len() + 1));
    Ok(out)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Func {
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
    Pow,
}

impl Func {
    fn lookup(name: &str) -> Option<(Func, usize)> {
        Some(match name {
            "sqrt" => (Func::Sqrt, 1),
            "cbrt" => (Func::Cbrt, 1),
            "exp" => (Func::Exp, 1),
            "ln" | "log" => (Func::Ln, 1),
            "sin" => (Func::Sin, 1),
            "cos" => (Func::Cos, 1),
            "tan" => (Func::Tan, 1),
            "atan" => (Func::Atan, 1),
            "abs" => (Func::Abs, 1),
            "sign" => (Func::Sign, 1),
            "min" => (Func::Min, 2),
            "max" => (Func::Max, 2),
            "pow" => (Func::Pow, 2),
            _ => return None,
        })
    }
}

/// Syntax tree (kept for the reference interpreter [`Expr::eval_tree`]).
#[derive(Clone, Debug)]
enum Ast {
    Num(f64),
    Var(u8),
    Neg(Box<Ast>),
    Bin(char, Box<Ast>, Box<Ast>),
    Call(Func, Vec<Ast>),
}

struct Parser<'a> {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    src: &'a str,
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }
    fn col(&self) -> usize {
        self.toks[self.pos].1
    }
    fn err(&self, kind: ExprErrorKind) -> ExprError {
        ExprError::new(kind, self.col(), self.src)
    }
    fn expected(&self, what: &str) -> ExprError {
        self.err(ExprErrorKind::Expected {
            expected: what.to_string(),
            found: self.peek().to_string(),
        })
    }
    fn eat(&mut self, c: char) -> bool {
        if *self.peek() == Tok::Sym(c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn enter(&mut self) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.err(ExprErrorKind::TooDeep));
        }
        Ok(())
    }

    fn expr(&mut self) -> Result<Ast, ExprError> {
        let mut lhs = self.term()?;
        while let Tok::Sym(c @ ('+' | '-')) = self.peek() {
            let op = *c;
            self.pos += 1;
            let rhs = self.term()?;
            lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        Ok(lhs)
    }
    fn term(&mut self) -> Result<Ast, ExprError> {
        let mut lhs = self.unary()?;
        while let Tok::Sym(c @ ('*' | '/')) = self.peek() {
            let op = *c;
            self.pos += 1;
            let rhs = self.unary()?;
            lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        Ok(lhs)
    }
    fn unary(&mut self) -> Result<Ast, ExprError> {
        self.enter()?;
        let r = if self.eat('-') {
            Ast::Neg(Box::new(self.unary()?))
        } else if self.eat('+') {
            self.unary()?
        } else {
            self.power()?
        };
        self.depth -= 1;
        Ok(r)
    }
    fn power(&mut self) -> Result<Ast, ExprError> {
        let base = self.primary()?;
        if self.eat('^') {
            let exp = self.unary()?;
            return Ok(Ast::Bin('^', Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }
    fn primary(&mut self) -> Result<Ast, ExprError> {
        let col = self.col();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.pos += 1;
                Ok(Ast::Num(v))
            }
            Tok::Sym('(') => {
                self.pos += 1;
                let e = self.expr()?;
                if !self.eat(')') {
                    return Err(self.expected("')'"));
                }
                Ok(e)
            }
            Tok::Ident(name) => {
                self.pos += 1;
                if *self.peek() == Tok::Sym('(') {
                    let Some((func, arity)) = Func::lookup(&name) else {
                        let kind = if matches!(name.as_str(), "x" | "y" | "z" | "pi") {
                            ExprErrorKind::NotAFunction(name)
                        } else {
                            ExprErrorKind::UnknownFunction(name)
                        };
                        return Err(ExprError::new(kind, col, self.src));
                    };
                    self.pos += 1;
                    let mut args = vec![self.expr()?];
                    while self.eat(',') {
                        args.push(self.expr()?);
                    }
                    if !self.eat(')') {
                        return Err(self.expected("',' or ')'"));
                    }
                    if args.len() != arity {
                        return Err(ExprError::new(
                            ExprErrorKind::Arity {
                                name,
                                expected: arity,
                                found: args.len(),
                            },
                            col,
                            self.src,
                        ));
                    }
                    return Ok(Ast::Call(func, args));
                }
                match name.as_str() {
                    "x" => Ok(Ast::Var(0)),
                    "y" => Ok(Ast::Var(1)),
                    "z" => Ok(Ast::Var(2)),
                    "pi" => Ok(Ast::Num(std::f64::consts::PI)),
                    _ if Func::lookup(&name).is_some() => Err(ExprError::new(
                        ExprErrorKind::Expected {
                            expected: format!("'(' after function '{name}'"),
                            found: self.peek().to_string(),
                        },
                        self.col(),
                        self.src,
                    )),
                    _ => Err(ExprError::new(
                        ExprErrorKind::UnknownVariable(name),
                        col,
                        self.src,
                    )),
                }
            }
            Tok::End if self.pos == 0 => Err(self.err(ExprErrorKind::Empty)),
            _ => Err(self.expected("a number, variable, function or '('")),
        }
    }
}

fn eval_ast(a: &Ast, p: [f64; 3]) -> f64 {
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
enum Op {
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

fn func_op(f: Func) -> Op {
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

fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        a // 0, -0 or NaN
    }
}

#[inline(always)]
fn apply(op: Op, a: f64, b: f64) -> f64 {
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

/// One SSA instruction: `reg[first_temp + k] = op(reg[a], reg[b])`.
#[derive(Clone, Copy, Debug)]
struct Ins {
    op: Op,
    a: u32,
    b: u32,
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
                if *f == Func::Pow {
                    self.pow(a, b)
                } else {
                    self.emit(func_op(*f), a, b)
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
        let toks = tokenize(src)?;
        let mut p = Parser {
            toks,
            pos: 0,
            src,
            depth: 0,
        };
        let ast = p.expr()?;
        if *p.peek() != Tok::End {
            let what = if matches!(p.peek(), Tok::Sym(')')) {
                "an operator or end of input (unbalanced ')')"
            } else {
                "an operator or end of input"
            };
            return Err(p.expected(what));
        }
        let mut b = Builder {
            consts: Vec::new(),
            const_ids: HashMap::new(),
            code: Vec::new(),
            memo: HashMap::new(),
        };
        let out = b.lower(&ast);
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
        Ok(Expr {
            source: src.to_string(),
            ast,
            init,
            code,
            result: reg(out),
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
        eval_ast(&self.ast, p.to_array())
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

fn dual(op: Op, a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
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
