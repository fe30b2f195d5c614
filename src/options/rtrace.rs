//! rtrace's (ttrace's) command line: the rendering and run parameters tpict reads, with
//! rtrace's defaults (`rtrace -defaults`: `-dt .03 -dc .75 -ds .2 -dr 2 -u+ -aa .1 -ar 256
//! -ad 1024 -as 512 -lr -10`), and rtrace's own options: `-f` input/output formats, `-o`
//! output specifiers, `-h` header, `-x`/`-y` flush interval and record count, `-I`
//! irradiance at the ray origin, `-ld` limit distance.

use super::render::RenderParams;
use super::run::RunParams;
use super::words::{bool_option, expand_args, unsupported, OptError};

/// A record format (`-f`): text, 32-bit or 64-bit floats (native byte order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `a`: text.
    Ascii,
    /// `f`: 32-bit floats.
    Float,
    /// `d`: 64-bit floats.
    Double,
}

impl Format {
    fn from_letter(c: char) -> Option<Format> {
        match c {
            'a' => Some(Format::Ascii),
            'f' => Some(Format::Float),
            'd' => Some(Format::Double),
            _ => None,
        }
    }

    /// The header's `FORMAT=` word.
    pub fn header_name(self) -> &'static str {
        match self {
            Format::Ascii => "ascii",
            Format::Float => "float",
            Format::Double => "double",
        }
    }
}

/// The output specifier letters ttrace knows (`-o`).
pub const OUTPUT_LETTERS: &str = "vodpnNlLwmMs";

/// rtrace's own options.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceParams {
    /// Input record format.
    pub input: Format,
    /// Output record format.
    pub output: Format,
    /// Output specifiers, in order (letters of [`OUTPUT_LETTERS`]).
    pub spec: String,
    /// `-h`: write a header.
    pub header: bool,
    /// `-x`: flush the output after this many records (0: at the end or when input pauses).
    pub flush: usize,
    /// `-y`: with `-x`, stop after `x·y` records.
    pub yres: usize,
    /// `-I`: irradiance at the ray origin, the direction as the surface normal.
    pub irradiance_at_origin: bool,
    /// `-ld`: limit each ray to the length of its direction vector.
    pub limit_distance: bool,
    /// `-f?c`: the values as a Radiance picture of `-x` × `-y` pixels.
    pub picture: bool,
}

impl Default for TraceParams {
    fn default() -> Self {
        TraceParams {
            input: Format::Ascii,
            output: Format::Ascii,
            spec: "v".into(),
            header: true,
            flush: 0,
            yres: 0,
            irradiance_at_origin: false,
            limit_distance: false,
            picture: false,
        }
    }
}

/// Everything rtrace's (and ttrace's) command line can say.
#[derive(Clone, Debug, PartialEq)]
pub struct RtraceOptions {
    /// Rendering parameters, with rtrace's defaults.
    pub params: RenderParams,
    /// Run parameters (threads, ambient files, warnings, error file).
    pub run: RunParams,
    /// rtrace's own options.
    pub trace: TraceParams,
    /// Scene files (octrees, scene files); none: an error (the rays come on standard input).
    pub scene_files: Vec<String>,
}

/// rtrace's rendering defaults (`rtrace -defaults`), where they differ from rpict's.
pub fn rtrace_defaults() -> RenderParams {
    RenderParams {
        dt: 0.03,
        dc: 0.75,
        ds: 0.2,
        dr: 2,
        u: true,
        aa: 0.1,
        ar: 256,
        ad: 1024,
        as_: 512,
        lr: -10,
        lw: 1e-4,
        ..RenderParams::default()
    }
}

/// What a ttrace command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum TraceCommand {
    /// Trace with these options.
    Trace(Box<RtraceOptions>),
    /// `-version`.
    PrintVersion,
    /// `--help`: print [`trace_help`].
    PrintHelp,
}

/// ttrace's usage.
pub fn trace_help() -> String {
    // Each line is its own literal: a `\` line continuation would eat the indentation.
    let mut s = [
        "usage: ttrace [rtrace options] [Tessera options] scene.rad|scene.oct ... < rays",
        "",
        "Traces the rays read on standard input (origin and direction per record) through",
        "Radiance scene files or octrees, as rtrace does, with rtrace's defaults. Options:",
        "  -f[afd][afdc]     input and output format: a text, f 32-bit, d 64-bit floats;",
        "                    c: the values as a Radiance picture of -x by -y pixels",
        "  -o[vodpnNlLwmMs]  output per ray: v value, o origin, d direction, p hit point,",
        "                    n normal facing the ray, N surface normal, l/L distance,",
        "                    w weight, m modifier, M material, s surface name",
        "  -I[+-]            irradiance at the origin (the direction is the surface normal)",
        "  -i[+-]            irradiance at the first surface hit",
        "  -h[+-]            header (default on)",
        "  -x N              flush every N records",
        "  -y N              with -x, stop after x*y records",
        "  -ld[+-]           limit the distance",
        "  -n N              threads (values do not depend on it at -ab 0)",
        "  -af FILE, --amb-log FILE, -e FILE, -w[+-], --max-primitives N, --allow-commands,",
        "  --obj-material NAME, and rtrace's -d* -s* -l* -a* -m* -u -bv.",
    ]
    .join("\n");
    s.push('\n');
    s
}

fn apply_trace_option(t: &mut TraceParams, words: &[String]) -> Result<Option<usize>, OptError> {
    let w = words[0].as_str();
    if let Some(b) = bool_option(w, "h", t.header) {
        t.header = b;
        return Ok(Some(1));
    }
    if let Some(b) = bool_option(w, "I", t.irradiance_at_origin) {
        t.irradiance_at_origin = b;
        return Ok(Some(1));
    }
    if let Some(b) = bool_option(w, "ld", t.limit_distance) {
        t.limit_distance = b;
        return Ok(Some(1));
    }
    if let Some(letters) = w.strip_prefix("-f") {
        let c: Vec<char> = letters.chars().collect();
        let bad = || OptError::BadValue {
            option: w.to_string(),
            reason: "expected -f followed by one or two of a, f, d (input, then output format)"
                .into(),
        };
        match c.as_slice() {
            [i] => {
                let f = Format::from_letter(*i).ok_or_else(bad)?;
                t.input = f;
                t.output = f;
            }
            [i, 'c'] => {
                t.input = Format::from_letter(*i).ok_or_else(bad)?;
                t.picture = true;
            }
            [i, o] => {
                t.input = Format::from_letter(*i).ok_or_else(bad)?;
                t.output = Format::from_letter(*o).ok_or_else(bad)?;
                t.picture = false;
            }
            _ => return Err(bad()),
        }
        return Ok(Some(1));
    }
    if let Some(letters) = w.strip_prefix("-o") {
        if letters.is_empty() {
            return Ok(None);
        }
        if let Some(c) = letters.chars().find(|c| !OUTPUT_LETTERS.contains(*c)) {
            return Err(unsupported(
                w,
                &format!("output letter '{c}' is not implemented (ttrace knows {OUTPUT_LETTERS})"),
            ));
        }
        t.spec = letters.to_string();
        return Ok(Some(1));
    }
    let count = |words: &[String]| -> Result<usize, OptError> {
        let a = words.get(1).ok_or_else(|| OptError::MissingArgument {
            option: words[0].clone(),
            expected: "a count".into(),
            got: 0,
        })?;
        a.parse::<usize>().map_err(|_| OptError::BadNumber {
            option: words[0].clone(),
            expected: "a non-negative integer".into(),
            got: a.clone(),
        })
    };
    match w {
        "-x" => {
            t.flush = count(words)?;
            Ok(Some(2))
        }
        "-y" => {
            t.yres = count(words)?;
            Ok(Some(2))
        }
        _ => Ok(None),
    }
}

/// Parse ttrace's arguments (without argv[0]), as rtrace reads them: options, then the
/// scene files or octree.
pub fn parse_rtrace_args(args: &[String]) -> Result<TraceCommand, OptError> {
    let words = expand_args(args)?;
    let mut o = RtraceOptions {
        params: rtrace_defaults(),
        run: RunParams::default(),
        trace: TraceParams::default(),
        scene_files: Vec::new(),
    };
    let mut i = 0;
    while i < words.len() {
        let w = &words[i];
        if !(w.len() > 1 && w.starts_with('-')) {
            o.scene_files.push(w.clone());
            i += 1;
            continue;
        }
        if let Some(scene) = o.scene_files.first() {
            return Err(OptError::OptionAfterScene {
                option: w.clone(),
                scene: scene.clone(),
            });
        }
        let rest = &words[i..];
        if let Some(n) = apply_trace_option(&mut o.trace, rest)? {
            i += n;
            continue;
        }
        if let Some(n) = o.params.apply_option(rest)? {
            i += n;
            continue;
        }
        match w.as_str() {
            "-S" | "-o" | "--stats" => {
                return Err(unsupported(w, "not an rtrace option"));
            }
            "-version" | "--version" => return Ok(TraceCommand::PrintVersion),
            "--help" | "-help" | "-defaults" => return Ok(TraceCommand::PrintHelp),
            "-P" | "-PP" => {
                return Err(unsupported(
                    w,
                    "persistent server mode is not implemented; use -n for threads",
                ))
            }
            _ => {}
        }
        if let Some(n) = o.run.apply_option(rest)? {
            i += n;
            continue;
        }
        return Err(OptError::Unknown(w.clone()));
    }
    if o.scene_files.is_empty() {
        return Err(OptError::BadValue {
            option: "scene".into(),
            reason: "no scene files or octree given (the rays come on standard input)".into(),
        });
    }
    if o.trace.irradiance_at_origin && o.params.i {
        return Err(OptError::BadValue {
            option: "-I".into(),
            reason: "-I and -i ask for different irradiances: give one".into(),
        });
    }
    Ok(TraceCommand::Trace(Box::new(o)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<TraceCommand, OptError> {
        let a: Vec<String> = s.split_whitespace().map(String::from).collect();
        parse_rtrace_args(&a)
    }

    #[test]
    fn rtraces_options_and_defaults() {
        let TraceCommand::Trace(o) =
            parse("-h- -ffd -ovpnm -I+ -x 10 -y 2 -ab 2 -n 3 scene.oct").unwrap()
        else {
            panic!()
        };
        assert!(!o.trace.header && o.trace.irradiance_at_origin);
        assert_eq!(
            (o.trace.input, o.trace.output),
            (Format::Float, Format::Double)
        );
        assert_eq!(o.trace.spec, "vpnm");
        assert_eq!((o.trace.flush, o.trace.yres), (10, 2));
        assert_eq!(o.params.ab, 2);
        assert_eq!((o.params.dt, o.params.dr, o.params.lr), (0.03, 2, -10));
        assert!(o.params.u);
        assert_eq!(o.run.threads, Some(3));
        assert_eq!(o.scene_files, ["scene.oct"]);
        let e = parse("-oq s.oct").unwrap_err().to_string();
        assert!(e.contains("'q'"), "{e}");
        let TraceCommand::Trace(o) = parse("-ffc -x 4 -y 2 s.oct").unwrap() else {
            panic!()
        };
        assert!(o.trace.picture && o.trace.input == Format::Float);
        assert!(parse("-fx s.oct").is_err());
        assert!(parse("-I -i s.oct").is_err());
        assert!(parse("-ab 1").is_err());
        assert!(parse("-S 1 s.oct").is_err());
    }
}
