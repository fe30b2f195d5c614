//! Scene reader: text → flat list of [`Primitive`]s, expanding inline commands.
//!
//! - Primitives are `modifier type identifier`, then `nS s..`, `nI i..`, `nR r..`; `alias`
//!   takes a single word (the aliased identifier) instead of counts, which ends up as its only
//!   string argument.
//! - `!xform ...` and the generators of [`super::gen`] (`genbox gensky gendaylit genprism
//!   genrev genworm gensurf genblinds`) are built in (no shell), alone or piped into any
//!   number of `xform` stages (`!genrev ... | xform -rx 90`). Other commands, commands using
//!   other shell syntax, and built-in options that are not implemented run through `sh -c`
//!   only when [`ReadOptions::allow_commands`] is set; their standard output is read as
//!   scene text located at `<command: ...>`.
//! - Files named by `xform` are looked up like real xform does: an absolute path as is, a
//!   relative one in each [`ReadOptions::raypath`] directory in turn (Radiance's default
//!   RAYPATH `.` is the current directory, *not* the including file's directory).
//!   Top-level files are opened as given.
//! - Top-level octrees are read by [`super::read_scene_files`] ([`super::octree`]); octrees
//!   named by `xform` are refused.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::error::SceneError;
use super::gen;
use super::lexer::{is_int, is_real, split_pipeline, Lexer, Token, TokenKind};
use super::primitive::{Location, Primitive};
use super::xform::{parse_xform_args, parse_xform_stdin_args, XformArgError};

/// Maximum nesting of inline commands (a file that includes itself hits this).
pub const MAX_DEPTH: u32 = 32;

/// Every type keyword of the scene language (Radiance's 59 types including `alias`).
pub const KNOWN_TYPES: &[&str] = &[
    "polygon",
    "cone",
    "sphere",
    "ring",
    "cylinder",
    "cup",
    "bubble",
    "tube",
    "source",
    "instance",
    "mesh",
    "plastic",
    "metal",
    "glass",
    "trans",
    "dielectric",
    "plastic2",
    "metal2",
    "trans2",
    "interface",
    "plasfunc",
    "metfunc",
    "glow",
    "light",
    "illum",
    "spotlight",
    "mist",
    "mirror",
    "transfunc",
    "BRTDfunc",
    "BSDF",
    "aBSDF",
    "WGMDfunc",
    "plasdata",
    "metdata",
    "transdata",
    "antimatter",
    "prism1",
    "prism2",
    "ashik2",
    "brightfunc",
    "brightdata",
    "brighttext",
    "colorpict",
    "colorfunc",
    "colordata",
    "colortext",
    "spectrum",
    "specfile",
    "specfunc",
    "specdata",
    "specpict",
    "texfunc",
    "texdata",
    "mixfunc",
    "mixdata",
    "mixtext",
    "mixpict",
    "alias",
];

/// How to read scenes.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Run inline commands other than the built-in ones (`xform`, the generators) through
    /// `sh -c`.
    pub allow_commands: bool,
    /// Directories searched for files named by `xform` (Radiance's RAYPATH).
    pub raypath: Vec<PathBuf>,
    /// `--obj-material NAME`: the modifier of the triangles of `.obj` files given as scene
    /// files that have no modifier name or an undefined one.
    pub obj_material: Option<String>,
    /// `--max-primitives N`: most primitives the scene may expand to (its text, inline
    /// commands, generators and `xform` arrays together; instances are not expanded).
    pub max_primitives: usize,
}

/// The default of [`ReadOptions::max_primitives`]: 2²² (about 4 GB of memory while the
/// scene is built).
pub const DEFAULT_MAX_PRIMITIVES: usize = 1 << 22;

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            allow_commands: false,
            raypath: Vec::new(),
            obj_material: None,
            max_primitives: DEFAULT_MAX_PRIMITIVES,
        }
    }
}

/// For a file `name` not found along the RAYPATH but next to the scene file `from` that
/// names it: a hint to add that folder to the RAYPATH (Radiance finds files along the
/// RAYPATH only, not beside the file naming them). Empty otherwise.
pub fn raypath_hint(name: &str, from: &str) -> String {
    let Some(dir) = Path::new(from)
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
    else {
        return String::new();
    };
    if Path::new(name).is_relative() && dir.join(name).is_file() {
        let d = dir.display();
        format!(
            " (it is in {d}, the folder of {from}: add that folder to RAYPATH, e.g. RAYPATH=.:{d})"
        )
    } else {
        String::new()
    }
}

/// Refuse a scene that expands to more than `opts.max_primitives` primitives: `n` would be
/// held at once, made by what is at `loc`.
fn check_count(n: usize, opts: &ReadOptions, loc: &Location) -> Result<(), SceneError> {
    if n > opts.max_primitives {
        return Err(SceneError::syntax(
            loc.clone(),
            format!(
                "the scene expands to more than {} primitives here (inline commands, \
                 generators and xform arrays multiply them; raise the limit with \
                 --max-primitives N)",
                opts.max_primitives
            ),
        ));
    }
    Ok(())
}

/// The location of primitives made from the command line (a `.obj` scene file).
pub const COMMAND_LINE: &str = "<command line>";

/// The mesh primitive standing for a `.obj` file given as a scene file:
/// `void mesh STEM 1 file.obj 0 0`, or `3 file.obj -m NAME` with a default modifier.
pub fn obj_scene_primitive(file: &str, default: Option<&str>) -> Primitive {
    let stem = Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty() && !s.contains(char::is_whitespace))
        .unwrap_or_else(|| "obj".into());
    let mut sargs = vec![file.to_string()];
    if let Some(d) = default {
        sargs.extend(["-m".to_string(), d.to_string()]);
    }
    Primitive {
        modifier: "void".into(),
        ptype: "mesh".into(),
        name: stem,
        sargs,
        iargs: Vec::new(),
        rargs: Vec::new(),
        loc: Location::new(COMMAND_LINE, 0),
    }
}

impl ReadOptions {
    /// raypath from $RAYPATH (':'-separated; default "."), allow_commands from
    /// TESSERA_ALLOW_COMMANDS=1.
    pub fn from_env() -> ReadOptions {
        let rp = std::env::var("RAYPATH").unwrap_or_default();
        let mut raypath: Vec<PathBuf> = rp
            .split(':')
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
            .collect();
        if raypath.is_empty() {
            raypath.push(PathBuf::from("."));
        }
        ReadOptions {
            allow_commands: std::env::var("TESSERA_ALLOW_COMMANDS").is_ok_and(|v| v == "1"),
            raypath,
            ..ReadOptions::default()
        }
    }
}

/// [`super::read_scene_files`] for scene text only (octrees refused).
pub fn read_text_files(paths: &[String], opts: &ReadOptions) -> Result<Vec<Primitive>, SceneError> {
    let mut out = Vec::new();
    for p in paths {
        if p == "-" {
            let loc = Location::new("<stdin>", 0);
            let text = read_text(std::io::stdin().lock(), "-", &loc)?;
            parse_into(&text, Arc::from("<stdin>"), opts, 0, &mut out)?;
            continue;
        }
        if p.starts_with('!') {
            // A command given where a file goes (oconv's `'!cmd'` arguments, rad's
            // `scene= '!xform ...'`): read as the one line of an inline command.
            parse_into(p, Arc::from("<command argument>"), opts, 0, &mut out)?;
            continue;
        }
        let loc = Location::new(p.as_str(), 0);
        let text = read_file(Path::new(p), p, &loc)?;
        parse_into(&text, Arc::from(p.as_str()), opts, 0, &mut out)?;
    }
    Ok(out)
}

/// Parse scene text (for tests and commands' output).
pub fn parse_scene_text(
    text: &str,
    file: &str,
    opts: &ReadOptions,
) -> Result<Vec<Primitive>, SceneError> {
    let mut out = Vec::new();
    parse_into(text, Arc::from(file), opts, 0, &mut out)?;
    Ok(out)
}

fn read_file(path: &Path, named: &str, loc: &Location) -> Result<String, SceneError> {
    if named.ends_with(".oct") {
        return Err(SceneError::Octree {
            loc: loc.clone(),
            path: named.to_string(),
        });
    }
    let file = std::fs::File::open(path).map_err(|e| SceneError::Io {
        loc: loc.clone(),
        path: named.to_string(),
        reason: e.to_string(),
    })?;
    read_text(file, named, loc)
}

/// Longest line of scene text accepted (a generous bound: Radiance's own lines are short).
pub const MAX_LINE: usize = 64 << 20;

/// Largest scene text accepted from one file or stream.
pub const MAX_SCENE_TEXT: u64 = 4 << 30;

/// Read scene text from `r` in chunks, refusing what cannot be a scene before it exhausts
/// memory: a NUL byte (binary data, such as `/dev/zero`), a line longer than [`MAX_LINE`],
/// more than [`MAX_SCENE_TEXT`] bytes, or text that is not UTF-8.
fn read_text(mut r: impl Read, named: &str, loc: &Location) -> Result<String, SceneError> {
    let fail = |reason: String| SceneError::Io {
        loc: loc.clone(),
        path: named.to_string(),
        reason,
    };
    let mut bytes: Vec<u8> = Vec::new();
    let mut chunk = vec![0u8; 1 << 20];
    let mut line = 0usize;
    loop {
        let n = match r.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(fail(e.to_string())),
        };
        let part = &chunk[..n];
        if let Some(i) = part.iter().position(|&b| b == 0) {
            return Err(fail(format!(
                "binary data (a NUL byte at byte {}): not scene text",
                bytes.len() + i
            )));
        }
        for &b in part {
            line = if b == b'\n' { 0 } else { line + 1 };
            if line > MAX_LINE {
                return Err(fail(format!(
                    "a line longer than {} MiB: not scene text",
                    MAX_LINE >> 20
                )));
            }
        }
        if (bytes.len() + n) as u64 > MAX_SCENE_TEXT {
            return Err(fail(format!(
                "more than {} GiB of scene text",
                MAX_SCENE_TEXT >> 30
            )));
        }
        bytes.extend_from_slice(part);
    }
    String::from_utf8(bytes).map_err(|_| fail("not UTF-8 text (is it a binary file?)".to_string()))
}

/// Find a file named in a command: absolute as is, relative along the RAYPATH.
fn find_on_raypath(name: &str, opts: &ReadOptions) -> Option<PathBuf> {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.is_file().then(|| p.to_path_buf());
    }
    let dirs: Vec<PathBuf> = if opts.raypath.is_empty() {
        vec![PathBuf::from(".")]
    } else {
        opts.raypath.clone()
    };
    dirs.iter().map(|d| d.join(p)).find(|c| c.is_file())
}

struct Cursor<'a> {
    lx: Lexer<'a>,
    file: Arc<str>,
    /// Line of the last token read (where an unexpected end of file is reported).
    last_line: u32,
}

impl Cursor<'_> {
    fn loc(&self, line: u32) -> Location {
        Location {
            file: self.file.clone(),
            line,
        }
    }

    fn word(&mut self, start: u32, what: &str, prim: &str) -> Result<Token, SceneError> {
        match self.lx.next_token(false) {
            Ok(Some(t)) => {
                self.last_line = t.line;
                Ok(t)
            }
            Ok(None) => Err(SceneError::syntax(
                self.loc(self.last_line),
                format!("unexpected end of file: missing {what}{prim} (started at line {start})"),
            )),
            Err(e) => Err(SceneError::syntax(self.loc(e.line), e.reason)),
        }
    }

    fn count(&mut self, start: u32, what: &str, prim: &str) -> Result<usize, SceneError> {
        let t = self.word(start, &format!("{what} argument count"), prim)?;
        match t.text.parse::<usize>() {
            Ok(n) if is_int(&t.text) && n <= 100_000_000 => Ok(n),
            _ => Err(SceneError::syntax(
                self.loc(t.line),
                format!("bad {what} argument count '{}'{prim}", t.text),
            )),
        }
    }
}

fn parse_into(
    text: &str,
    file: Arc<str>,
    opts: &ReadOptions,
    depth: u32,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    let mut cur = Cursor {
        lx: Lexer::new(text),
        file,
        last_line: 1,
    };
    loop {
        let tok = match cur.lx.next_token(true) {
            Ok(Some(t)) => t,
            Ok(None) => return Ok(()),
            Err(e) => return Err(SceneError::syntax(cur.loc(e.line), e.reason)),
        };
        let start = tok.line;
        cur.last_line = start;
        let loc = cur.loc(start);
        if tok.kind == TokenKind::Command {
            expand_command(&tok.text, &loc, opts, depth, out)?;
            continue;
        }
        let modifier = tok.text;
        let ptype = cur.word(start, "type", "")?;
        if !KNOWN_TYPES.contains(&ptype.text.as_str()) {
            return Err(SceneError::syntax(
                cur.loc(ptype.line),
                format!(
                    "unknown primitive type '{}' (modifier '{modifier}')",
                    ptype.text
                ),
            ));
        }
        let ptype = ptype.text;
        let name = cur.word(start, "identifier", &format!(" of {ptype}"))?.text;
        let ctx = format!(" in {ptype} \"{name}\"");
        let mut prim = Primitive {
            modifier,
            ptype,
            name,
            sargs: Vec::new(),
            iargs: Vec::new(),
            rargs: Vec::new(),
            loc,
        };
        if prim.ptype == "alias" {
            let t = cur.word(start, "aliased identifier", &ctx)?;
            prim.sargs.push(t.text);
            check_count(out.len() + 1, opts, &prim.loc)?;
            out.push(prim);
            continue;
        }
        let ns = cur.count(start, "string", &ctx)?;
        for k in 0..ns {
            let t = cur.word(start, &format!("string argument {} of {ns}", k + 1), &ctx)?;
            prim.sargs.push(t.text);
        }
        let ni = cur.count(start, "integer", &ctx)?;
        for k in 0..ni {
            let t = cur.word(start, &format!("integer argument {} of {ni}", k + 1), &ctx)?;
            match t.text.parse::<i64>() {
                Ok(v) if is_int(&t.text) => prim.iargs.push(v),
                _ => {
                    return Err(SceneError::syntax(
                        cur.loc(t.line),
                        format!(
                            "integer argument {} '{}' is not an integer{ctx}",
                            k + 1,
                            t.text
                        ),
                    ))
                }
            }
        }
        let nr = cur.count(start, "real", &ctx)?;
        for k in 0..nr {
            let t = cur.word(start, &format!("real argument {} of {nr}", k + 1), &ctx)?;
            match t.text.parse::<f64>() {
                Ok(v) if is_real(&t.text) && v.is_finite() => prim.rargs.push(v),
                _ => {
                    return Err(SceneError::syntax(
                        cur.loc(t.line),
                        format!("real argument {} '{}' is not a number{ctx}", k + 1, t.text),
                    ))
                }
            }
        }
        check_count(out.len() + 1, opts, &prim.loc)?;
        out.push(prim);
    }
}

fn program_name(cmd: &str) -> String {
    cmd.split_whitespace().next().unwrap_or("").to_string()
}

fn expand_command(
    cmd: &str,
    loc: &Location,
    opts: &ReadOptions,
    depth: u32,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    if depth >= MAX_DEPTH {
        return Err(SceneError::Recursion {
            loc: loc.clone(),
            depth,
            command: cmd.to_string(),
        });
    }
    let stages = split_pipeline(cmd).map_err(|e| SceneError::syntax(loc.clone(), e))?;
    let mut unsupported = None;
    if let Some(stages) = &stages {
        match builtin_pipeline(stages, loc, opts, depth)? {
            Builtin::Done(prims) => {
                check_count(out.len().saturating_add(prims.len()), opts, loc)?;
                super::primitive::append_prims(out, prims);
                return Ok(());
            }
            Builtin::Unsupported(r) => unsupported = Some(r),
            Builtin::NotBuiltIn => {}
        }
    }
    if !opts.allow_commands {
        return Err(SceneError::CommandNotAllowed {
            loc: loc.clone(),
            name: program_name(cmd),
            command: cmd.to_string(),
            note: unsupported.map(|r| format!(" ({r})")).unwrap_or_default(),
        });
    }
    let text = run_shell(cmd, loc)?;
    parse_into(
        &text,
        Arc::from(format!("<command: {cmd}>")),
        opts,
        depth + 1,
        out,
    )
}

/// What the built-in commands made of a pipeline.
enum Builtin {
    /// Its output.
    Done(Vec<Primitive>),
    /// A stage uses an option that is not built in (why).
    Unsupported(String),
    /// A stage is not a built-in command.
    NotBuiltIn,
}

/// Run a pipeline of built-in commands: a first stage `xform` (with files), `genbox` or
/// another built-in generator ([`gen::GENERATORS`]), then any number of `xform` stages
/// reading their standard input.
fn builtin_pipeline(
    stages: &[Vec<String>],
    loc: &Location,
    opts: &ReadOptions,
    depth: u32,
) -> Result<Builtin, SceneError> {
    let syntax = |r: String| SceneError::syntax(loc.clone(), r);
    let first = &stages[0];
    let name = first[0].as_str();
    if name != "xform" && !gen::GENERATORS.contains(&name) {
        return Ok(Builtin::NotBuiltIn);
    }
    let mut later = Vec::new();
    for st in &stages[1..] {
        if st[0] != "xform" {
            return Ok(Builtin::NotBuiltIn);
        }
        match parse_xform_stdin_args(&st[1..]) {
            Ok(x) => later.push(x),
            Err(XformArgError::Bad(r)) => return Err(syntax(r)),
            Err(XformArgError::Unsupported(r)) => return Ok(Builtin::Unsupported(r)),
        }
    }
    let mut prims = Vec::new();
    if name == "xform" {
        match parse_xform_args(&first[1..]) {
            Ok(x) => run_xform(&x, loc, opts, depth, &mut prims)?,
            Err(XformArgError::Bad(r)) => return Err(syntax(r)),
            Err(XformArgError::Unsupported(r)) => return Ok(Builtin::Unsupported(r)),
        }
    } else {
        let cx = gen::GenContext {
            loc,
            raypath: &opts.raypath,
            max_primitives: opts.max_primitives,
        };
        match gen::generate(first, &cx) {
            Some(Ok(p)) => prims = p,
            Some(Err(gen::ArgError::Bad(r))) => return Err(syntax(r)),
            Some(Err(gen::ArgError::Unsupported(r))) => return Ok(Builtin::Unsupported(r)),
            None => return Ok(Builtin::NotBuiltIn),
        }
    }
    for x in &later {
        check_count(prims.len().saturating_mul(x.copies.len()), opts, loc)?;
        let mut next = Vec::with_capacity(prims.len() * x.copies.len());
        for copy in &x.copies {
            for p in &prims {
                let q = x
                    .apply(copy, p)
                    .map_err(|r| SceneError::syntax(p.loc.clone(), format!("xform: {r}")))?;
                next.push(q);
            }
        }
        prims = next;
    }
    Ok(Builtin::Done(prims))
}

fn run_shell(cmd: &str, loc: &Location) -> Result<String, SceneError> {
    let fail = |reason: String| SceneError::CommandFailed {
        loc: loc.clone(),
        command: cmd.to_string(),
        reason,
    };
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(cmd)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| fail(format!("cannot run sh: {e}")))?;
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        let err = err.trim().replace('\n', "; ");
        return Err(fail(format!("{} ({err})", o.status)));
    }
    String::from_utf8(o.stdout).map_err(|_| fail("output is not UTF-8 text".to_string()))
}

fn run_xform(
    x: &super::xform::XformCommand,
    loc: &Location,
    opts: &ReadOptions,
    depth: u32,
    out: &mut Vec<Primitive>,
) -> Result<(), SceneError> {
    let mut contents: Vec<Vec<Primitive>> = Vec::new();
    for f in &x.files {
        if f == "-" {
            return Err(SceneError::syntax(
                loc.clone(),
                "xform: reading standard input is not allowed inline",
            ));
        }
        if f.ends_with(".oct") {
            return Err(SceneError::Octree {
                loc: loc.clone(),
                path: f.clone(),
            });
        }
        let path = find_on_raypath(f, opts).ok_or_else(|| SceneError::Io {
            loc: loc.clone(),
            path: f.clone(),
            reason: format!(
                "not found on RAYPATH {:?}{}",
                opts.raypath,
                raypath_hint(f, &loc.file)
            ),
        })?;
        let text = read_file(&path, f, loc)?;
        let mut prims = Vec::new();
        let shown = path.to_string_lossy().into_owned();
        parse_into(&text, Arc::from(shown), opts, depth + 1, &mut prims)?;
        contents.push(prims);
    }
    let each: usize = contents.iter().map(Vec::len).sum();
    check_count(
        out.len()
            .saturating_add(each.saturating_mul(x.copies.len())),
        opts,
        loc,
    )?;
    for copy in &x.copies {
        for prims in &contents {
            for p in prims {
                let q = x
                    .apply(copy, p)
                    .map_err(|r| SceneError::syntax(p.loc.clone(), format!("xform: {r}")))?;
                out.push(q);
            }
        }
    }
    Ok(())
}
