//! Errors of the function language: compile-time ([`CalError`]) and run-time
//! ([`EvalError`]).

use std::fmt;

/// A compile-time error: a syntax error, an unreadable file, or an error while folding a
/// constant expression. Always fatal for the scene that caused it.
///
/// Displays as `file:line:col: message` (`file: message` when there is no line, e.g. a file
/// that cannot be found). For an expression given to [`super::CalBuilder::expr`], `file`
/// and `line` come from the primitive's origin and `col` is the column within the
/// expression text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CalError {
    /// File name (as found on the RAYPATH), or the origin of an expression.
    pub file: String,
    /// 1-based line; 0 when the error is about the whole file.
    pub line: u32,
    /// 1-based column (bytes) of the lookahead where the error was found.
    pub col: u32,
    /// What is wrong (Radiance's wording where it has one, e.g. `')' expected`).
    pub message: String,
}

impl CalError {
    pub(crate) fn file(file: &str, message: impl Into<String>) -> CalError {
        CalError {
            file: file.to_string(),
            line: 0,
            col: 0,
            message: message.into(),
        }
    }
}

impl fmt::Display for CalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.col, self.message
            )
        }
    }
}

impl std::error::Error for CalError {}

/// A run-time error of one evaluation.
///
/// `Domain` and `Range` are Radiance master's compute errors: the caller skips the
/// primitive for this ray (a pattern leaves the colour unchanged). `Fatal` errors
/// (undefined names, too few arguments, `arg(n)` past the end, recursion too deep) stop
/// the render in Radiance; the message names the name and where it was defined or used.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum EvalError {
    /// A NaN result (library function or `^`), or `select` out of range.
    Domain,
    /// An infinite result (library function or `^`), or a division by zero.
    Range,
    /// An error that makes the scene unusable.
    Fatal(String),
}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvalError::Domain => write!(f, "domain error"),
            EvalError::Range => write!(f, "range error"),
            EvalError::Fatal(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for EvalError {}
