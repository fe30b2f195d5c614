//! The function language of `genrev`, `genworm` and `gensurf`: the curve or surface
//! functions given on the command line (`z(t)`, `x(s,t)`…) with the `-e expr` and
//! `-f file` definitions, compiled by Tessera's `.cal` compiler in the plain dialect
//! (no ray channels) with what those programs predefine: `PI` and the cubic curves
//! `hermite`, `bezier`, `bspline`.
//!
//! As in the real programs, `-e` and `-f` definitions are compiled in command-line order
//! into the global context (a `-f` file is found along the RAYPATH), then the functions
//! given on the command line, under names of their own (so `-e 'x(t)=t*t'` with the
//! argument `'x(t)'` means t², and does not change an argument `t`).

use std::path::PathBuf;
use std::sync::Arc;

use crate::cal::{CalBuilder, CalOptions, Ctx, Dialect, FuncRef, Program};

use super::ArgError;

/// What the generators predefine (the cubic curves as in Tessera's rayinit.cal).
const PRELUDE: &str = "PI : 3.14159265358979323846;
hermite(p0,p1,r0,r1,t) = p0*((2*t-3)*t*t+1) + p1*(3-2*t)*t*t +
\tr0*((t-2)*t+1)*t + r1*(t-1)*t*t;
bezier(p1,p2,p3,p4,t) = p1*(1-t)*(1-t)*(1-t) + 3*p2*t*(1-t)*(1-t) +
\t3*p3*t*t*(1-t) + p4*t*t*t;
bspline(pp,p0,p1,pn,t) = (pp*(1-t)*(1-t)*(1-t) + p0*((3*t-6)*t*t+4) +
\tp1*(((-3*t+3)*t+3)*t+1) + pn*t*t*t) / 6;
";

/// A definition option, in command-line order.
#[derive(Clone, Debug, PartialEq)]
pub enum CalDef {
    /// `-e expr`: statements.
    Expr(String),
    /// `-f file`: a function file found along the RAYPATH.
    File(String),
}

/// Compiled functions, called by name order of [`Funcs::compile`]'s `defs`.
pub struct Funcs {
    prog: Arc<Program>,
    funcs: Vec<FuncRef>,
    /// `valid(s,t)` if it is defined with two parameters (gensurf).
    pub valid: Option<FuncRef>,
    prog_name: &'static str,
    names: Vec<String>,
}

impl Funcs {
    /// Compile `opts` then each `(name, params, body)` of `defs` as `name(params)=body;`.
    pub fn compile(
        prog_name: &'static str,
        opts: &[CalDef],
        defs: &[(&str, &str, &str)],
        raypath: &[PathBuf],
    ) -> Result<Funcs, ArgError> {
        let bad = |e: String| ArgError::Bad(format!("{prog_name}: {e}"));
        let copts = CalOptions {
            dialect: Dialect::Plain,
            fold: true,
            rayinit: false,
        };
        let mut b = CalBuilder::with_options(raypath, copts).map_err(|e| bad(e.to_string()))?;
        b.load_text(PRELUDE.as_bytes(), "<generator prelude>", Ctx::GLOBAL)
            .map_err(|e| bad(e.to_string()))?;
        for o in opts {
            match o {
                CalDef::Expr(e) => b
                    .load_text(e.as_bytes(), "<-e>", Ctx::GLOBAL)
                    .map_err(|e| bad(e.to_string()))?,
                CalDef::File(f) => {
                    let path = super::find_on_raypath(f, raypath).ok_or_else(|| {
                        bad(format!(
                            "cannot find function file '{f}' on RAYPATH {raypath:?}"
                        ))
                    })?;
                    let text = std::fs::read(&path)
                        .map_err(|e| bad(format!("cannot read '{}': {e}", path.display())))?;
                    b.load_text(&text, &path.display().to_string(), Ctx::GLOBAL)
                        .map_err(|e| bad(e.to_string()))?;
                }
            }
        }
        let mut funcs = Vec::new();
        for (name, params, body) in defs {
            // Under a name of its own: as in the real programs, `-e 'x(t)=…'` neither
            // replaces the command line's x(t) nor is hidden by it, and the command line
            // may call a function x(t) defined by `-e`.
            let internal = format!("{name}_tessera_gen_");
            let stmt = format!("{internal}({params})={body};");
            b.load_text(stmt.as_bytes(), &format!("<{name}({params})>"), Ctx::GLOBAL)
                .map_err(|e| bad(format!("{name}({params}) = {body}: {e}")))?;
            funcs.push(
                b.func(&internal, Ctx::GLOBAL)
                    .map_err(|e| bad(e.to_string()))?,
            );
        }
        let valid = b
            .definitions()
            .iter()
            .any(|(n, p)| n == "valid" && *p == Some(2))
            .then(|| b.func("valid", Ctx::GLOBAL))
            .transpose()
            .map_err(|e| bad(e.to_string()))?;
        Ok(Funcs {
            prog: b.finish(),
            funcs,
            valid,
            prog_name,
            names: defs.iter().map(|(n, p, _)| format!("{n}({p})")).collect(),
        })
    }

    /// Call function `k` of the definitions.
    pub fn call(&self, k: usize, args: &[f64]) -> Result<f64, ArgError> {
        self.call_ref(self.funcs[k], &self.names[k], args)
    }

    /// Call a resolved function.
    pub fn call_ref(&self, f: FuncRef, what: &str, args: &[f64]) -> Result<f64, ArgError> {
        let env = crate::cal::Env::default();
        let mut ev = self.prog.begin(&env);
        let v = ev.call(f, args).map_err(|e| {
            ArgError::Bad(format!(
                "{}: evaluating {what} at {args:?}: {e}",
                self.prog_name
            ))
        })?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ArgError::Bad(format!(
                "{}: {what} at {args:?} is not finite",
                self.prog_name
            )))
        }
    }
}
