//! [`CalBuilder`]: loads `.cal` files and compiles expressions into one [`Program`].

use super::code::{Code, Def, Loc, Node, NodeId, Slot, SlotId};
use super::library::Lib;
use super::program::Program;
use super::{CalError, CalOptions, Ctx, Dialect, ExprId, FuncRef};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Tessera's own ray initialisation file, used when the RAYPATH has no `rayinit.cal`.
pub const BUILTIN_RAYINIT: &str = include_str!("rayinit.cal");

/// Tessera's own versions of Radiance library files that generated scenes name (written
/// from the published models, `src/cal/lib/`), used when the RAYPATH has none.
pub const BUILTIN_LIBRARY: [(&str, &str); 5] = [
    ("skybright.cal", include_str!("lib/skybright.cal")),
    ("source.cal", include_str!("lib/source.cal")),
    ("perezlum.cal", include_str!("lib/perezlum.cal")),
    ("rev.cal", include_str!("lib/rev.cal")),
    ("surf.cal", include_str!("lib/surf.cal")),
];

/// The path recorded for a built-in library file that was used (a scene's inputs list it,
/// so that a job copies its text and workers fingerprint the same file).
pub fn builtin_library_path(name: &str) -> PathBuf {
    PathBuf::from(format!("<built-in {name}>"))
}

/// The text behind a path made by [`builtin_library_path`].
pub fn builtin_library_text(path: &Path) -> Option<&'static str> {
    let s = path.to_str()?;
    builtin_library(s.strip_prefix("<built-in ")?.strip_suffix('>')?)
}

/// The built-in text of library file `name`, if Tessera has one.
pub fn builtin_library(name: &str) -> Option<&'static str> {
    BUILTIN_LIBRARY
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
}

/// The ray channel variables `$1..$27`, in order (§1.8).
pub const CHANNELS: [&str; 27] = [
    "Dx", "Dy", "Dz", "Nx", "Ny", "Nz", "Px", "Py", "Pz", "T", "Rdot", "S", "Tx", "Ty", "Tz", "Ix",
    "Iy", "Iz", "Jx", "Jy", "Jz", "Kx", "Ky", "Kz", "Ts", "Lu", "Lv",
];

/// The variables only BRDF materials define, in [`super::Env::brdf`] order.
pub const BRDF_VARS: [&str; 7] = ["NxP", "NyP", "NzP", "RdotP", "CrP", "CgP", "CbP"];

/// Compiles `.cal` files and expressions; [`CalBuilder::finish`] makes the [`Program`].
pub struct CalBuilder {
    pub(crate) code: Code,
    /// Depth of each node's tree (building only).
    pub(crate) depth: Vec<u32>,
    pub(crate) opts: CalOptions,
    names: HashMap<String, SlotId>,
    pub(super) ctxs: Vec<String>,
    loaded: HashMap<String, Ctx>,
    /// Function files read from disk: (name as given, path), in load order.
    paths: Vec<(String, PathBuf)>,
    file_ids: HashMap<String, u32>,
    raypath: Vec<PathBuf>,
    pub(super) exprs: Vec<NodeId>,
    outputs: Vec<(u32, ExprId)>,
    warnings: Vec<String>,
    rayinit: String,
}

/// The next outer context of `ctx` (its first level stripped), or None for global.
fn outer(ctx: &str) -> Option<&str> {
    if ctx.is_empty() {
        return None;
    }
    Some(ctx[1..].find('`').map_or("", |i| &ctx[i + 1..]))
}

impl CalBuilder {
    /// A builder for the renderer, with the ray channel names and `rayinit.cal` (the first
    /// one on `raypath`, or Tessera's built-in one).
    pub fn new(raypath: &[PathBuf]) -> Result<CalBuilder, CalError> {
        CalBuilder::with_options(raypath, CalOptions::default())
    }

    /// A builder with explicit options.
    pub fn with_options(raypath: &[PathBuf], opts: CalOptions) -> Result<CalBuilder, CalError> {
        let mut b = CalBuilder {
            code: Code::default(),
            depth: Vec::new(),
            opts,
            names: HashMap::new(),
            ctxs: vec![String::new()],
            loaded: HashMap::new(),
            paths: Vec::new(),
            file_ids: HashMap::new(),
            raypath: raypath.to_vec(),
            exprs: Vec::new(),
            outputs: Vec::new(),
            warnings: Vec::new(),
            rayinit: String::new(),
        };
        if opts.dialect == Dialect::Renderer {
            let file = b.file_id("<ray channels>");
            for (i, name) in CHANNELS.iter().enumerate() {
                let loc = Loc { file, line: 0 };
                let e = b.push_node(Node::Chan(i as u32 + 1), loc, 1);
                b.define(name, "", 0, false, e, loc);
            }
            for (i, name) in BRDF_VARS.iter().enumerate() {
                let s = b.lookup_def(name, "");
                b.code.slots[s as usize].def = Def::Brdf(i as u8);
                b.code.slots[s as usize].def_loc = Loc { file, line: 0 };
            }
        }
        if opts.rayinit {
            let found = raypath
                .iter()
                .map(|d| d.join("rayinit.cal"))
                .find(|p| p.is_file());
            match found {
                Some(p) => {
                    let text = std::fs::read(&p)
                        .map_err(|e| CalError::file(&p.display().to_string(), e.to_string()))?;
                    let name = p.display().to_string();
                    b.load_text(&text, &name, Ctx::GLOBAL)?;
                    b.rayinit = name;
                }
                None => {
                    b.load_text(
                        BUILTIN_RAYINIT.as_bytes(),
                        "<tessera rayinit.cal>",
                        Ctx::GLOBAL,
                    )?;
                    b.rayinit = "built-in".into();
                }
            }
            b.loaded.insert("rayinit.cal".into(), Ctx::GLOBAL);
        }
        Ok(b)
    }

    /// Which `rayinit.cal` was loaded: its path, `built-in`, or empty (none).
    pub fn rayinit(&self) -> &str {
        &self.rayinit
    }

    /// Warnings so far (redefinitions, definitions hiding library functions, `:`
    /// definitions whose value is not constant), Radiance's wording.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    fn find(&self, name: &str) -> Option<PathBuf> {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.is_file().then(|| p.to_path_buf());
        }
        if self.raypath.is_empty() {
            return p.is_file().then(|| p.to_path_buf());
        }
        self.raypath.iter().map(|d| d.join(p)).find(|c| c.is_file())
    }

    /// Load a function file (once per name) and return its context: `` `name`` for
    /// `name.cal` (directories and a `.cal` suffix stripped), global for `"."`.
    pub fn load_file(&mut self, name: &str) -> Result<Ctx, CalError> {
        if name == "." {
            return Ok(Ctx::GLOBAL);
        }
        if let Some(c) = self.loaded.get(name) {
            return Ok(*c);
        }
        let (text, path) = match self.find(name) {
            Some(path) => {
                let text = std::fs::read(&path)
                    .map_err(|e| CalError::file(&path.display().to_string(), e.to_string()))?;
                self.paths.push((name.to_string(), path.clone()));
                (text, path)
            }
            // Radiance's library files a scene names most (gensky's skybright.cal,
            // gendaylit's perezlum.cal, genrev's rev.cal, gensurf's surf.cal, ies2rad's
            // source.cal): Tessera's own versions when Radiance's are not found.
            None => match builtin_library(name) {
                Some(t) => {
                    let path = builtin_library_path(name);
                    self.paths.push((name.to_string(), path.clone()));
                    (t.as_bytes().to_vec(), path)
                }
                None => {
                    return Err(CalError::file(
                        name,
                        format!("cannot find function file on RAYPATH {:?}", self.raypath),
                    ))
                }
            },
        };
        let base = Path::new(name)
            .file_name()
            .map_or(name.to_string(), |s| s.to_string_lossy().into_owned());
        let stem = match base.len().checked_sub(4) {
            Some(i) if base.is_char_boundary(i) && base[i..].eq_ignore_ascii_case(".cal") => {
                &base[..i]
            }
            _ => &base[..],
        };
        let ctx = self.context(stem);
        self.load_text(&text, &path.display().to_string(), ctx)?;
        self.loaded.insert(name.to_string(), ctx);
        Ok(ctx)
    }

    /// The context named `` `name`` (created if new).
    pub fn context(&mut self, name: &str) -> Ctx {
        let s = format!("`{name}");
        match self.ctxs.iter().position(|c| *c == s) {
            Some(i) => Ctx(i as u32),
            None => {
                self.ctxs.push(s);
                Ctx(self.ctxs.len() as u32 - 1)
            }
        }
    }

    /// A function-name argument, resolved in context `ctx` as a call would be. The name
    /// may be defined later (or never: calling it is then a fatal error).
    pub fn func(&mut self, name: &str, ctx: Ctx) -> Result<FuncRef, CalError> {
        let ok = name
            .bytes()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == b'`')
            && name
                .bytes()
                .all(|c| c.is_ascii_alphanumeric() || b"_.`".contains(&c));
        if !ok {
            return Err(CalError::file(name, "illegal function name"));
        }
        let cstr = self.ctxs[ctx.0 as usize].clone();
        Ok(FuncRef(self.lookup_ref(name, &cstr)))
    }

    /// Every defined name (fully qualified, e.g. `` v`foo``), with its number of
    /// parameters for a function (None for a variable or constant). In slot order.
    pub fn definitions(&self) -> Vec<(String, Option<usize>)> {
        self.code
            .slots
            .iter()
            .filter_map(|s| match s.def {
                Def::None => None,
                Def::Func { nparams, .. } => Some((s.name.clone(), Some(nparams as usize))),
                _ => Some((s.name.clone(), None)),
            })
            .collect()
    }

    /// The rcalc-style outputs (`$N = expr`) compiled so far.
    pub fn outputs(&self) -> &[(u32, ExprId)] {
        &self.outputs
    }

    /// The function files read from disk so far: (name as given, path found), in load
    /// order (built-in files are not listed).
    pub fn file_paths(&self) -> &[(String, PathBuf)] {
        &self.paths
    }

    /// The immutable program.
    pub fn finish(mut self) -> Arc<Program> {
        self.code.link();
        Arc::new(Program::new(self.code, self.exprs, self.outputs))
    }

    // ---- for the parser ----

    pub(super) fn file_id(&mut self, file: &str) -> u32 {
        if let Some(i) = self.file_ids.get(file) {
            return *i;
        }
        self.code.files.push(file.to_string());
        let i = self.code.files.len() as u32 - 1;
        self.file_ids.insert(file.to_string(), i);
        i
    }

    pub(crate) fn push_node(&mut self, n: Node, loc: Loc, depth: u32) -> NodeId {
        self.code.nodes.push(n);
        self.code.locs.push(loc);
        self.depth.push(depth);
        self.code.nodes.len() as NodeId - 1
    }

    pub(crate) fn add_output(&mut self, n: u32, e: NodeId) {
        self.exprs.push(e);
        self.outputs.push((n, ExprId(self.exprs.len() as u32 - 1)));
    }

    fn slot(&mut self, qualified: String, written: &str) -> SlotId {
        if let Some(s) = self.names.get(&qualified) {
            return *s;
        }
        let lib = if written.contains('`') {
            None
        } else {
            Lib::lookup(written, self.opts.dialect)
        };
        self.code.slots.push(Slot {
            name: qualified.clone(),
            def: Def::None,
            def_loc: Loc::default(),
            lib,
        });
        let s = self.code.slots.len() as SlotId - 1;
        self.names.insert(qualified, s);
        s
    }

    /// The slot a reference to `name` binds to in context `ctx` (§1.6): `` v` `` global,
    /// `` `v`` local only, otherwise the most qualified existing name, else a new local.
    pub(crate) fn lookup_ref(&mut self, name: &str, ctx: &str) -> SlotId {
        if let Some(g) = name.strip_suffix('`') {
            return self.slot(g.to_string(), name);
        }
        if let Some(l) = name.strip_prefix('`') {
            return self.slot(format!("{l}{ctx}"), name);
        }
        let mut c = Some(ctx);
        while let Some(cx) = c {
            if let Some(s) = self.names.get(&format!("{name}{cx}")) {
                return *s;
            }
            c = outer(cx);
        }
        self.slot(format!("{name}{ctx}"), name)
    }

    /// The slot a definition of `name` in context `ctx` goes to.
    pub(crate) fn lookup_def(&mut self, name: &str, ctx: &str) -> SlotId {
        if let Some(g) = name.strip_suffix('`') {
            return self.slot(g.to_string(), name);
        }
        let l = name.strip_prefix('`').unwrap_or(name);
        self.slot(format!("{l}{ctx}"), name)
    }

    /// Define `name` (a variable, or a function of `nparams` parameters).
    pub(crate) fn define(
        &mut self,
        name: &str,
        ctx: &str,
        nparams: usize,
        konst: bool,
        body: NodeId,
        loc: Loc,
    ) {
        let s = self.lookup_def(name, ctx);
        let value = match self.code.nodes[body as usize] {
            Node::Num(v) => Some(v),
            _ => None,
        };
        let slot = &self.code.slots[s as usize];
        let q = slot.name.clone();
        match slot.def {
            Def::None if slot.lib.is_some() => self
                .warnings
                .push(format!("{q}: definition hides library function")),
            Def::None => {}
            Def::Num(_) | Def::Var { konst: true, .. } | Def::Func { konst: true, .. } => {
                self.warnings.push(format!("{q}: constant redefined"))
            }
            _ => self.warnings.push(format!("{q}: redefined")),
        }
        let def = if nparams > 0 {
            Def::Func {
                nparams: nparams.min(u16::MAX as usize) as u16,
                body,
                konst,
            }
        } else if konst {
            match value {
                Some(v) => Def::Num(v),
                None => {
                    self.warnings
                        .push(format!("{q}: assigned non-constant value"));
                    Def::Var {
                        expr: body,
                        konst: true,
                    }
                }
            }
        } else {
            Def::Var {
                expr: body,
                konst: false,
            }
        };
        let slot = &mut self.code.slots[s as usize];
        slot.def = def;
        slot.def_loc = loc;
    }
}
