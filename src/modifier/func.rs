//! The function language in a scene: one [`CalBuilder`] while the scene is read, one
//! [`Program`] after, shared by every pattern, texture, mixture and material that
//! evaluates expressions ([`FuncCall`]).
//!
//! Only scenes that use functions create the builder (and load `rayinit.cal`): a scene
//! without them renders exactly as before. A run-time error Radiance treats as fatal
//! (an undefined name, too few arguments, `arg(n)` past the end, the recursion limit) is
//! recorded once ([`FuncShared::fatal`]); renders stop at the next row and the tools report
//! it with a non-zero exit. Domain and range errors skip the primitive for that ray, as
//! Radiance does.

use super::frame::PatternFrame;
use crate::cal::{CalBuilder, Ctx, Env, EvalError, Evaluation, ExprId, FuncRef, Program, Pure};
use crate::render::shading::ShadingPoint;
use crate::scene::primitive::Primitive;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// What the function modifiers of one scene share: the program (set when the scene is
/// built) and the first fatal run-time error.
#[derive(Debug, Default)]
pub struct FuncShared {
    program: OnceLock<Arc<Program>>,
    fatal: OnceLock<String>,
}

impl FuncShared {
    /// The scene's program (None before the scene is built).
    pub fn program(&self) -> Option<&Arc<Program>> {
        self.program.get()
    }

    /// The first fatal evaluation error, if one happened.
    pub fn fatal(&self) -> Option<&str> {
        self.fatal.get().map(String::as_str)
    }

    /// Record a fatal error (the first one is kept).
    pub fn report(&self, msg: String) {
        let _ = self.fatal.set(msg);
    }
}

/// The function language state of a scene being read.
#[derive(Default)]
pub struct SceneFunctions {
    raypath: Vec<PathBuf>,
    builder: Mutex<Option<CalBuilder>>,
    shared: Arc<FuncShared>,
    /// The function files read (name as given, path), kept when the program is linked.
    paths: Mutex<Vec<(String, PathBuf)>>,
}

impl std::fmt::Debug for SceneFunctions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneFunctions")
            .field("raypath", &self.raypath)
            .finish_non_exhaustive()
    }
}

impl SceneFunctions {
    /// No functions yet; files will be found along `raypath`.
    pub fn new(raypath: &[PathBuf]) -> SceneFunctions {
        SceneFunctions {
            raypath: raypath.to_vec(),
            builder: Mutex::new(None),
            shared: Arc::new(FuncShared::default()),
            paths: Mutex::new(Vec::new()),
        }
    }

    /// Run `f` with the scene's builder (created, with `rayinit.cal`, on first use).
    pub fn with<R>(
        &self,
        f: impl FnOnce(&mut CalBuilder) -> Result<R, String>,
    ) -> Result<R, String> {
        let mut g = self
            .builder
            .lock()
            .map_err(|_| "function language state poisoned".to_string())?;
        if g.is_none() {
            *g = Some(CalBuilder::new(&self.raypath).map_err(|e| e.to_string())?);
        }
        f(g.as_mut().expect("just created"))
    }

    /// The function files read from disk: (name as given, path found).
    pub fn file_paths(&self) -> Vec<(String, PathBuf)> {
        if let Ok(g) = self.builder.lock() {
            if let Some(b) = g.as_ref() {
                return b.file_paths().to_vec();
            }
        }
        self.paths.lock().map(|p| p.clone()).unwrap_or_default()
    }

    /// The state the scene's function modifiers share.
    pub fn shared(&self) -> Arc<FuncShared> {
        self.shared.clone()
    }

    /// Link the program (when any primitive used functions) and hand out the shared
    /// state; None when the scene has no functions.
    pub fn finish(&self) -> Option<Arc<FuncShared>> {
        let b = self.builder.lock().ok()?.take()?;
        if let Ok(mut p) = self.paths.lock() {
            *p = b.file_paths().to_vec();
        }
        let _ = self.shared.program.set(b.finish());
        Some(self.shared.clone())
    }
}

/// One primitive's use of the function language: its context, frame and real arguments.
#[derive(Clone, Debug)]
pub struct FuncCall {
    shared: Arc<FuncShared>,
    frame: PatternFrame,
    args: Vec<f64>,
    /// Where the primitive was defined (for fatal errors).
    origin: String,
}

/// The context of a primitive's function file (its string argument `ff`).
pub fn load_context(b: &mut CalBuilder, ff: &str) -> Result<Ctx, String> {
    b.load_file(ff).map_err(|e| e.to_string())
}

/// Compile expression `text` in `ctx` for primitive `p`.
pub fn compile(b: &mut CalBuilder, p: &Primitive, text: &str, ctx: Ctx) -> Result<ExprId, String> {
    b.expr(text, ctx, &p.loc.to_string())
        .map_err(|e| e.to_string())
}

/// Resolve function name `name` in `ctx`.
pub fn function(b: &mut CalBuilder, name: &str, ctx: Ctx) -> Result<FuncRef, String> {
    b.func(name, ctx).map_err(|e| e.to_string())
}

impl FuncCall {
    /// The call state of primitive `p` whose transform words start at string argument
    /// `xf_at`.
    pub fn new(shared: Arc<FuncShared>, p: &Primitive, xf_at: usize) -> Result<FuncCall, String> {
        let words = p.sargs.get(xf_at..).unwrap_or(&[]);
        Ok(FuncCall {
            shared,
            frame: PatternFrame::from_words(words)?,
            args: p.rargs.clone(),
            origin: format!("{} {} {}", p.loc, p.ptype, p.name),
        })
    }

    /// The frame the primitive evaluates in.
    pub fn frame(&self) -> &PatternFrame {
        &self.frame
    }

    /// The primitive's real arguments.
    pub fn args(&self) -> &[f64] {
        &self.args
    }

    /// The scene's program, unless none was made or a fatal error was recorded (then
    /// [`FuncCall::eval`] skips the primitive too).
    pub fn live_program(&self) -> Option<&Arc<Program>> {
        let prog = self.shared.program()?;
        self.shared.fatal().is_none().then_some(prog)
    }

    /// Evaluate at `sp` with `f`, which gets an evaluation; None (the primitive is skipped
    /// for this ray) on a domain or range error, a non-finite result or a fatal error
    /// (which is recorded).
    pub fn eval<R>(
        &self,
        sp: &ShadingPoint,
        brdf: Option<[f64; 7]>,
        f: impl FnOnce(&mut Evaluation) -> Result<R, EvalError>,
    ) -> Option<R> {
        let prog = self.shared.program()?;
        if self.shared.fatal().is_some() {
            return None;
        }
        let env = Env {
            chan: self.frame.channels(sp),
            args: &self.args,
            brdf,
        };
        let mut ev = prog.begin(&env);
        match f(&mut ev) {
            Ok(r) => Some(r),
            Err(EvalError::Fatal(m)) => {
                self.shared.report(format!("{}: {m}", self.origin));
                None
            }
            Err(_) => None,
        }
    }
}

/// A primitive's expressions as one pure expression (`crate::cal::Pure`), when all of
/// them are; decided at the first evaluation, once the scene's program is linked.
#[derive(Debug, Default)]
pub struct PureExprs(OnceLock<Option<Pure>>);

impl PureExprs {
    /// The pure form of `exprs`, made at its first use for the primitive's own arguments
    /// (which every evaluation passes); None when they have none.
    fn form(&self, call: &FuncCall, exprs: &[ExprId]) -> Option<&Pure> {
        let prog = call.live_program()?;
        self.0
            .get_or_init(|| prog.pure_exprs_with(exprs, Some(call.args())))
            .as_ref()
    }

    /// The ray channels the pure form of `exprs` reads ([`crate::modifier::Pattern::reads`]);
    /// None when they have none.
    pub fn reads(&self, call: &FuncCall, exprs: &[ExprId]) -> Option<u32> {
        self.form(call, exprs).map(Pure::channels_read)
    }

    /// The values of `exprs` (at most three) at `sp` by their pure form: None when they are
    /// not all pure or the evaluation leaves them to the machine (then
    /// [`FuncCall::eval`] gives the same values, or the error).
    pub fn values(&self, call: &FuncCall, exprs: &[ExprId], sp: &ShadingPoint) -> Option<[f64; 3]> {
        let pure = self.form(call, exprs)?;
        let mut out = [0.0; 3];
        let o = out.get_mut(..exprs.len())?;
        let chan = call.frame().channels_for(sp, pure.channels_read());
        pure.eval_into(&chan, call.args(), &[], o)?;
        Some(out)
    }
}

/// `Ok(v)` if finite, else a range error (a NaN or infinity never leaves an evaluation).
pub fn finite(v: f64) -> Result<f64, EvalError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(EvalError::Range)
    }
}
