//! Parse errors of expressions (ours), with the column where they were detected.

/// What went wrong in an expression (see [`ExprError`] for the position).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[allow(missing_docs)] // variant fields: named in the variant's docs and message
pub enum ExprErrorKind {
    /// A token other than the `expected` one was `found`.
    /// A character that starts no token.
    /// A malformed number literal.
    /// A name that is neither `x`, `y`, `z` nor `pi`.
    /// A call of an unknown function.
    /// A function `name` called with the wrong number of arguments.
    /// A call of a variable or constant (`x(...)`).
    /// No expression at all.
    /// Nesting deeper than the parser allows.
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
    /// What went wrong.
    pub kind: ExprErrorKind,
    /// 1-based column; `input.chars().count() + 1` for "end of input".
    pub column: usize,
    /// The expression's text.
    pub input: String,
    caret: String,
}

impl ExprError {
    pub(super) fn new(kind: ExprErrorKind, column: usize, input: &str) -> Self {
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
pub(super) const MAX_DEPTH: usize = 256;
