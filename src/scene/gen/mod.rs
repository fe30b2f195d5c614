//! Built-in scene generators: Radiance's `genbox`, `gensky`, `gendaylit`, `genprism`,
//! `genrev`, `genworm`, `gensurf` and `genblinds`, run inside the scene reader.
//!
//! Each generator parses the words after its program name and returns the primitives the
//! real program (Radiance 6.0a) prints, in its order, with its names and its numbers: values
//! are rounded as the real program prints them (`%18.12g` for geometry, `%.3e` and `%f` for
//! skies), so a scene reads the same whether a generator runs built in or through a shell.
//! Comment lines are not reproduced. Options a generator does not build in are reported as
//! [`ArgError::Unsupported`], so the reader can run the real program when commands are
//! allowed, or name the command and the option when they are not.
//! `tests/generators.rs` checks each generator against the real program.

pub mod blinds;
pub mod daylit;
pub mod funcs;
pub mod genbox;
pub mod prism;
pub mod rev;
pub mod sky;
pub mod solar;
pub mod surf;
pub mod worm;

use std::path::{Path, PathBuf};

use super::primitive::{Location, Primitive};

/// Why generator arguments were not accepted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ArgError {
    /// Valid for the real program but not built in (run the real program if allowed).
    Unsupported(String),
    /// Invalid arguments (the real program would fail too, or produce no scene).
    Bad(String),
}

/// What a generator may need from the reader.
#[derive(Clone, Copy, Debug)]
pub struct GenContext<'a> {
    /// Where the command is (every primitive is located there).
    pub loc: &'a Location,
    /// Directories searched for function files (`-f`), Radiance's RAYPATH.
    pub raypath: &'a [PathBuf],
    /// Most primitives the scene may expand to ([`super::reader::ReadOptions::max_primitives`]).
    pub max_primitives: usize,
}

impl GenContext<'_> {
    /// Refuse to make more than [`GenContext::max_primitives`] primitives (`made` so far).
    pub(crate) fn check_made(&self, prog: &str, made: usize) -> Result<(), ArgError> {
        if made > self.max_primitives {
            return Err(ArgError::Bad(format!(
                "{prog} makes more than {} primitives, the scene's limit (raise it with \
                 --max-primitives N)",
                self.max_primitives
            )));
        }
        Ok(())
    }
}

/// The names of the built-in generators.
pub const GENERATORS: [&str; 8] = [
    "genbox",
    "gensky",
    "gendaylit",
    "genprism",
    "genrev",
    "genworm",
    "gensurf",
    "genblinds",
];

/// Run built-in generator `words[0]` with arguments `words[1..]`; None if `words[0]` is
/// not a built-in generator.
pub fn generate(words: &[String], cx: &GenContext) -> Option<Result<Vec<Primitive>, ArgError>> {
    let args = &words[1..];
    Some(match words.first()?.as_str() {
        "genbox" => genbox::genbox(args, cx.loc),
        "gensky" => sky::gensky(args, cx),
        "gendaylit" => daylit::gendaylit(args, cx),
        "genprism" => prism::genprism(args, cx),
        "genrev" => rev::genrev(args, cx),
        "genworm" => worm::genworm(args, cx),
        "gensurf" => surf::gensurf(args, cx),
        "genblinds" => blinds::genblinds(args, cx),
        _ => return None,
    })
}

/// A number argument: decimal notation as `atof` reads it, but the whole word must be a
/// number (a word `atof` would read as 0 is refused, with the program and `what` named).
pub(crate) fn num(prog: &str, what: &str, w: &str) -> Result<f64, ArgError> {
    let bad = || ArgError::Bad(format!("{prog}: {what} '{w}' is not a number"));
    if !super::lexer::is_real(w) {
        return Err(bad());
    }
    w.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(bad)
}

/// The argument after option `args[i]`, or a "missing value" error.
pub(crate) fn value<'a>(prog: &str, args: &'a [String], i: usize) -> Result<&'a str, ArgError> {
    args.get(i + 1)
        .map(String::as_str)
        .ok_or_else(|| ArgError::Bad(format!("{prog}: missing value for {}", args[i])))
}

/// A number following option `args[i]`.
pub(crate) fn opt_num(prog: &str, args: &[String], i: usize) -> Result<f64, ArgError> {
    num(
        prog,
        &format!("value for {}", args[i]),
        value(prog, args, i)?,
    )
}

/// `x` as printed by `%.Ng`-style `%.{digits-1}e` (`digits` significant digits) and read
/// back: the value a real generator's output holds.
pub(crate) fn sig(x: f64, digits: usize) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    format!("{:.*e}", digits - 1, x).parse().unwrap_or(x)
}

/// `%18.12g` as read back.
pub(crate) fn g12(x: f64) -> f64 {
    sig(x, 12)
}

/// `%f` (six decimals) as read back.
pub(crate) fn f6(x: f64) -> f64 {
    if !x.is_finite() {
        return x;
    }
    format!("{x:.6}").parse().unwrap_or(x)
}

/// `%.3e` as read back.
pub(crate) fn e3(x: f64) -> f64 {
    sig(x, 4)
}

/// A primitive without string or integer arguments.
pub(crate) fn prim(
    modifier: &str,
    ptype: &str,
    name: String,
    rargs: Vec<f64>,
    loc: &Location,
) -> Primitive {
    Primitive {
        modifier: modifier.to_string(),
        ptype: ptype.to_string(),
        name,
        sargs: Vec::new(),
        iargs: Vec::new(),
        rargs,
        loc: loc.clone(),
    }
}

/// Find a file named on a command line: absolute as is, relative along the RAYPATH
/// (Radiance's `getpath`, as real generators look up `-f` files).
pub(crate) fn find_on_raypath(name: &str, raypath: &[PathBuf]) -> Option<PathBuf> {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.is_file().then(|| p.to_path_buf());
    }
    if raypath.is_empty() {
        return p.is_file().then(|| p.to_path_buf());
    }
    raypath.iter().map(|d| d.join(p)).find(|c| c.is_file())
}

/// Bound on a generator's segment or grid counts, to keep bad input from exhausting memory.
pub(crate) const MAX_SEGMENTS: f64 = 10_000_000.0;

/// Round a segment count as the real generators do (to the nearest integer) and check it.
pub(crate) fn count(prog: &str, what: &str, w: &str) -> Result<usize, ArgError> {
    let v = num(prog, what, w)?;
    let n = (v + 0.5).floor();
    if n < 1.0 {
        return Err(ArgError::Bad(format!("{prog}: {what} must be at least 1")));
    }
    if n > MAX_SEGMENTS {
        return Err(ArgError::Bad(format!(
            "{prog}: {what} {w} is too large (at most {MAX_SEGMENTS})"
        )));
    }
    Ok(n as usize)
}
