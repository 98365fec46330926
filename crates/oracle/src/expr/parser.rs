//! The recursive-descent parser of expressions (ours), with the grammar of [`super`].

use super::error::{ExprError, ExprErrorKind, MAX_DEPTH};
use super::lexer::{Tok, tokenize};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Func {
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
pub(super) enum Ast {
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
