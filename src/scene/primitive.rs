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

/// Append `more` to `out` without holding both lists twice: when `out` is the shorter one
/// (a material before a large `gensurf`), its few primitives go in front of `more`, whose
/// storage is kept.
pub fn append_prims(out: &mut Vec<Primitive>, mut more: Vec<Primitive>) {
    if out.len() < more.len() {
        let head = std::mem::take(out);
        more.reserve_exact(head.len());
        more.splice(0..0, head);
        *out = more;
    } else {
        out.extend(more);
    }
}

/// Write primitives as scene text that reads back as the same primitives (every number in
/// its shortest exact form; an alias as `mod alias name target`), each after a blank line.
pub fn write_text(prims: &[Primitive], s: &mut String) {
    use std::fmt::Write;
    for p in prims {
        if p.ptype == "alias" {
            let target = p.sargs.first().map(String::as_str).unwrap_or("void");
            let _ = writeln!(s, "\n{} alias {} {}", p.modifier, p.name, target);
            continue;
        }
        let _ = writeln!(s, "\n{} {} {}", p.modifier, p.ptype, p.name);
        let _ = write!(s, "{}", p.sargs.len());
        for a in &p.sargs {
            let _ = write!(s, " {a}");
        }
        let _ = write!(s, "\n{}", p.iargs.len());
        for a in &p.iargs {
            let _ = write!(s, " {a}");
        }
        let _ = write!(s, "\n{}", p.rargs.len());
        for a in &p.rargs {
            let _ = write!(s, " {a}");
        }
        s.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prim(name: &str) -> Primitive {
        Primitive {
            modifier: "void".into(),
            ptype: "sphere".into(),
            name: name.into(),
            sargs: Vec::new(),
            iargs: Vec::new(),
            rargs: vec![0.0, 0.0, 0.0, 1.0],
            loc: Location::new("t.rad", 1),
        }
    }

    /// Appending keeps the order, whichever list is the longer.
    #[test]
    fn append_keeps_order() {
        let names = |v: &[Primitive]| v.iter().map(|p| p.name.clone()).collect::<Vec<_>>();
        let mut out = vec![prim("a")];
        append_prims(&mut out, vec![prim("b"), prim("c")]);
        assert_eq!(names(&out), ["a", "b", "c"]);
        append_prims(&mut out, vec![prim("d")]);
        assert_eq!(names(&out), ["a", "b", "c", "d"]);
        append_prims(&mut out, Vec::new());
        let mut empty = Vec::new();
        append_prims(&mut empty, out);
        assert_eq!(names(&empty), ["a", "b", "c", "d"]);
    }
}
