//! Scene primitives: the `modifier type identifier` records of a Radiance scene file.

use std::fmt;
use std::sync::Arc;

/// Where a primitive (or an error) comes from: a file (or `<stdin>`, or a command) and a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// File name as given (after RAYPATH lookup), `<stdin>`, or `<command: ...>`.
    pub file: Arc<str>,
    /// 1-based line number where the primitive starts.
    pub line: u32,
}

impl Location {
    pub fn new(file: impl Into<Arc<str>>, line: u32) -> Self {
        Location {
            file: file.into(),
            line,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Line 0 is the file itself (it could not be opened or read): no line to name.
        if self.line == 0 {
            write!(f, "{}", self.file)
        } else {
            write!(f, "{}:{}", self.file, self.line)
        }
    }
}

/// One primitive, exactly as written (after inline commands and `xform` are expanded).
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    /// Modifier name (`void` for none).
    pub modifier: String,
    /// Type keyword (`polygon`, `plastic`, `alias`, ...).
    pub ptype: String,
    /// Identifier.
    pub name: String,
    /// String arguments.
    pub sargs: Vec<String>,
    /// Integer arguments (always empty in practice).
    pub iargs: Vec<i64>,
    /// Real arguments.
    pub rargs: Vec<f64>,
    /// Where the primitive starts.
    pub loc: Location,
}
