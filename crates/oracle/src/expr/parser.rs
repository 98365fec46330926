//! The recursive-descent parser of expressions (ours), with the grammar of [`super`].

use super::error::{ExprError, ExprErrorKind, MAX_DEPTH};
use super::eval::{Op, apply};
use super::lexer::{Tok, tokenize};

/// The instruction of the function `name` and its number of arguments.
fn lookup(name: &str) -> Option<(Op, usize)> {
    Some(match name {
        "sqrt" => (Op::Sqrt, 1),
        "cbrt" => (Op::Cbrt, 1),
        "exp" => (Op::Exp, 1),
        "ln" | "log" => (Op::Ln, 1),
        "sin" => (Op::Sin, 1),
        "cos" => (Op::Cos, 1),
        "tan" => (Op::Tan, 1),
        "atan" => (Op::Atan, 1),
        "abs" => (Op::Abs, 1),
        "sign" => (Op::Sign, 1),
        "min" => (Op::Min, 2),
        "max" => (Op::Max, 2),
        "pow" => (Op::Powf, 2),
        _ => return None,
    })
}

/// Syntax tree (kept for the reference interpreter [`Expr::eval_tree`]).
#[derive(Clone, Debug)]
pub(super) enum Ast {
    Num(f64),
    Var(u8),
    Neg(Box<Ast>),
    Bin(char, Box<Ast>, Box<Ast>),
    Call(Op, Vec<Ast>),
}

impl Ast {
    /// The reference interpreter of the syntax tree.
    pub(super) fn eval(&self, p: [f64; 3]) -> f64 {
        match self {
            Ast::Num(v) => *v,
            Ast::Var(i) => p[*i as usize],
            Ast::Neg(e) => -e.eval(p),
            Ast::Bin(op, l, r) => {
                let (l, r) = (l.eval(p), r.eval(p));
                match op {
                    '+' => l + r,
                    '-' => l - r,
                    '*' => l * r,
                    '/' => l / r,
                    _ => l.powf(r),
                }
            }
            Ast::Call(f, args) => {
                let a = args[0].eval(p);
                let b = args.get(1).map_or(0.0, |e| e.eval(p));
                apply(*f, a, b)
            }
        }
    }
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
        self.left_assoc(['+', '-'], Self::term)
    }
    fn term(&mut self) -> Result<Ast, ExprError> {
        self.left_assoc(['*', '/'], Self::unary)
    }
    /// `operand (op operand)*` for the two operators `ops`, grouped from the left.
    fn left_assoc(
        &mut self,
        ops: [char; 2],
        operand: fn(&mut Self) -> Result<Ast, ExprError>,
    ) -> Result<Ast, ExprError> {
        let mut lhs = operand(self)?;
        while let Tok::Sym(c) = self.peek() {
            let op = *c;
            if !ops.contains(&op) {
                break;
            }
            self.pos += 1;
            let rhs = operand(self)?;
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
                    let Some((func, arity)) = lookup(&name) else {
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
                    _ if lookup(&name).is_some() => Err(ExprError::new(
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

/// Parse `src` into a syntax tree (the whole input: trailing tokens are an error).
pub(super) fn parse_ast(src: &str) -> Result<Ast, ExprError> {
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
    Ok(ast)
}
