//! Radiance's function language (`.cal` files and the expressions of pattern, texture,
//! mixture and procedural-material primitives), from §1 of the format reference.
//!
//! # Use
//!
//! ```
//! use tessera::cal::{CalBuilder, Env};
//! let mut b = CalBuilder::new(&[]).unwrap(); // channel names + rayinit.cal
//! let ctx = b.load_file(".").unwrap(); // "." = the global context
//! let e = b.expr("Px*2 + A1", ctx, "scene.rad:12").unwrap();
//! let f = b.func("sq", ctx).unwrap(); // rayinit's sq(x) = x*x
//! let prog = b.finish(); // Arc<Program>: Send + Sync, immutable
//! let mut chan = [0.0; 27];
//! chan[6] = 0.5; // $7 = Px
//! let env = Env { chan, args: &[1.0], brdf: None };
//! let mut ev = prog.begin(&env); // one tick of the evaluation clock
//! assert_eq!(ev.eval(e), Ok(2.0));
//! assert_eq!(ev.call(f, &[3.0]), Ok(9.0));
//! ```
//!
//! - [`CalBuilder::new`]`(raypath)` defines the ray channel names (`Dx`=`$1` … `Lv`=`$27`,
//!   and the BRDF variables `NxP … CbP`, set only when [`Env::brdf`] is Some), then loads
//!   the first `rayinit.cal` on the RAYPATH (Radiance's, when installed) or Tessera's
//!   built-in one ([`BUILTIN_RAYINIT`]).
//! - [`CalBuilder::load_file`] loads a function file once per name into context
//!   `` `name`` (`"."` is the global context); [`CalBuilder::expr`] compiles a primitive's
//!   expression in a context; [`CalBuilder::func`] resolves a function-name argument.
//! - [`CalBuilder::finish`] links the code into a [`Program`]. [`Program::begin`] starts an
//!   [`Evaluation`] for one [`Env`] (one (modifier, ray) pair): variables are computed at
//!   most once within it, from a cache this thread keeps per program (no locks, no
//!   allocation in steady state; evaluations may nest).
//! - Compile errors are [`CalError`] (`file:line:col: message`); run-time errors are
//!   [`EvalError`]: `Domain`/`Range` (skip the primitive for this ray) or `Fatal`.
//! - [`icalc`] evaluates a standalone text, for tests and tools.
//!
//! # Semantics
//!
//! Lexer and grammar as Radiance's calexpr.c; names bound at parse time with contexts
//! (caldefn.c); constant folding (`:` definitions, constant functions, `x/c` → `x*(1/c)`,
//! "divide by zero constant", "bad constant expression", "ray parameter used in constant
//! expression"); lazy, per-call cached arguments; function names as arguments; master's
//! run-time error rules (NaN → domain, ±Inf → range from library calls and `^`; division
//! by zero → range; `select` out of range → domain). A finished program runs as stack
//! code (`vm`: one block per definition, expression and call argument, jumps for `if`
//! and `select`); constants fold through the tree walker (`eval`). Evaluation depth is
//! limited to [`MAX_DEPTH`] nested blocks (variables, calls and arguments) or [`MAX_STACK`]
//! bytes of stack (a fatal error, never a stack overflow); an expression's tree to 2000 levels and its parentheses,
//! calls and `^` to 200 (compile errors). Not implemented: `source_corr`, `source_theta`,
//! `source_phi`, `fprism_val` (the reference does not define them fully).
//! docs/functions.md describes the language, the dialects and the error rules.

mod builder;
mod code;
mod compile;
mod error;
mod eval;
mod fold;
mod lexer;
mod library;
mod noise;
mod parser;
mod program;
mod pure;
mod vm;

pub use builder::{
    builtin_library, builtin_library_path, builtin_library_text, CalBuilder, BRDF_VARS,
    BUILTIN_LIBRARY, BUILTIN_RAYINIT, CHANNELS,
};
pub use error::{CalError, EvalError};
pub use eval::{MAX_DEPTH, MAX_STACK};
pub use noise::{fnoise3, noise3};
pub use program::{Evaluation, Program};
pub use pure::{LaneInputs, Pure, LANES};

/// Which host's rules a text follows (§1.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dialect {
    /// The renderer: `$N` are ray channels, no `$N = e` statements, the renderer's library
    /// (`arg erf erfc noise3 noise3x/y/z fnoise3`) and ray channel names.
    Renderer,
    /// rcalc: `$N` are input fields (read from [`Env::chan`]), `$N = e` statements define
    /// outputs ([`Program::outputs`]); calfunc's library only.
    Rcalc,
    /// Plain (icalc, gensurf): no `$`, calfunc's library only.
    Plain,
}

/// How a [`CalBuilder`] compiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CalOptions {
    /// The dialect.
    pub dialect: Dialect,
    /// Constant folding (rcalc's `-n` and icalc have none).
    pub fold: bool,
    /// Load `rayinit.cal` (found on the RAYPATH, or the built-in one).
    pub rayinit: bool,
}

impl Default for CalOptions {
    /// The renderer's: folding, rayinit.
    fn default() -> CalOptions {
        CalOptions {
            dialect: Dialect::Renderer,
            fold: true,
            rayinit: true,
        }
    }
}

/// A context (`` `name`` of a loaded file, or global).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Ctx(pub(crate) u32);

impl Ctx {
    /// The global context (rayinit.cal and `.`).
    pub const GLOBAL: Ctx = Ctx(0);
}

/// A compiled expression of a [`Program`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ExprId(pub(crate) u32);

/// A function of a [`Program`], to call with values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FuncRef(pub(crate) u32);

/// What one evaluation sees of the ray and the primitive.
#[derive(Debug, Clone, Copy)]
pub struct Env<'a> {
    /// Ray channels `$1..$27` (§1.8: `Dx Dy Dz Nx Ny Nz Px Py Pz T Rdot S Tx Ty Tz Ix Iy Iz
    /// Jx Jy Jz Kx Ky Kz Ts Lu Lv`).
    pub chan: [f64; 27],
    /// The primitive's real arguments (`arg(n)`, `A1`…).
    pub args: &'a [f64],
    /// `NxP NyP NzP RdotP CrP CgP CbP`, defined only for BRDF materials.
    pub brdf: Option<[f64; 7]>,
}

impl Default for Env<'_> {
    fn default() -> Self {
        Env {
            chan: [0.0; 27],
            args: &[],
            brdf: None,
        }
    }
}

/// An error of [`icalc`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IcalcError {
    /// The text did not compile.
    #[error("{0}")]
    Compile(CalError),
    /// The expression did not evaluate.
    #[error("{0}")]
    Eval(EvalError),
}

/// Evaluate `expr` after the statements of `statements` (both in the global context), with
/// no RAYPATH (the built-in rayinit when `opts.rayinit`) and a zero [`Env`].
pub fn icalc(statements: &str, expr: &str, opts: CalOptions) -> Result<f64, IcalcError> {
    icalc_env(statements, expr, opts, &Env::default())
}

/// [`icalc`] with a given environment.
pub fn icalc_env(
    statements: &str,
    expr: &str,
    opts: CalOptions,
    env: &Env,
) -> Result<f64, IcalcError> {
    let mut b = CalBuilder::with_options(&[], opts).map_err(IcalcError::Compile)?;
    b.load_text(statements.as_bytes(), "<input>", Ctx::GLOBAL)
        .map_err(IcalcError::Compile)?;
    let e = b
        .expr(expr, Ctx::GLOBAL, "<expr>")
        .map_err(IcalcError::Compile)?;
    let prog = b.finish();
    let mut ev = prog.begin(env);
    ev.eval(e).map_err(IcalcError::Eval)
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_machine;
