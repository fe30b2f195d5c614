//! rpict's (tpict's) command line: the three kinds of parameters plus the scene files, parsed
//! in one pass (`@file`/`$VAR` expanded first, options before scene files), and printed back
//! as words.

use super::picture::PictureParams;
use super::render::RenderParams;
use super::run::RunParams;
use super::words::{expand_args, unsupported, OptError};

/// Everything rpict's (and tpict's) command line can say.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RpictOptions {
    /// Rendering parameters (the light transport).
    pub params: RenderParams,
    /// Picture parameters (view, resolution, pixel sampling).
    pub picture: PictureParams,
    /// Run parameters (threads, files, reports).
    pub run: RunParams,
    /// Scene files (after the options); `-` is stdin. Empty input means `["-"]`.
    pub scene_files: Vec<String>,
}

/// What a tpict command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Render with these options.
    Render(Box<RpictOptions>),
    /// `-defaults`/`-help`: print [`super::defaults_text`] of the options given before it.
    PrintDefaults(Box<RpictOptions>),
    /// `-version`, `--version`.
    PrintVersion,
    /// `--help`, `-h`: print [`help_text`].
    PrintHelp,
}

/// tpict's usage: rpict's options in brief and Tessera's own options in full.
pub fn help_text() -> String {
    // Each line is its own literal: a `\` line continuation would eat the indentation.
    let mut s: String = [
        "usage: tpict [rpict options] [Tessera options] scene.rad [more.rad ...]",
        "",
        "Renders Radiance scene files, octrees and Wavefront .obj files ('-' or none:",
        "stdin) with rpict's options:",
        "  views         -vt? -vp -vd -vu -vh -vv -vo -va -vs -vl -vf",
        "  picture       -x -y -pa -pj -ps -pt",
        "  direct light  -dt -dc -dj -ds -dr -dp -dv",
        "  specular      -ss -st",
        "  limits        -lr -lw",
        "  ambient       -av -aw -ab -aa -ar -ad -as -ae -ai -aE -aI -af",
        "  others        -i -u -bv -w -t -e -o -S, @file and $VAR",
        "'tpict -defaults' prints every value, as rpict does.",
        "",
        "Tessera's own options:",
        "  -n N                    render threads (default: every core, or SLURM_CPUS_PER_TASK)",
        "  -o FILE                 output: .hdr (Radiance), .exr or .png; -S n: a pattern",
        "  --allow-commands        run a scene's !commands other than xform and genbox",
        "  --obj-material NAME     modifier of .obj triangles with no or an undefined name",
        "  --max-primitives N      most primitives the scene may expand to (default 4194304)",
        "  --stats FILE            write render statistics (JSON)",
        "  --amb-log FILE          share ambient values through Tessera's append-only log",
        "  --amb-flush N           values per log write (default 128)",
        "  --amb-force             use a log made for another scene or other options",
        "  --no-overture           no cache-filling pass before the picture's own",
        "  --same-seeds            every frame samples each pixel as the first (less flicker)",
        "  -ax START END STEP      -aa per frame: START, less STEP each frame, down to END",
        "  -axg START END RATIO    -aa per frame: START, times RATIO each frame, down to END",
        "  -axt SECS START END     -aa per frame (-S) keeping each frame near SECS of CPU",
        "  -axm RELAX AHEAD        jobs: -aa x RELAX where the view is gone AHEAD frames on",
        "  --help, -h              this text; --version, -version: the version",
        "",
        "The ambient calculation's additions to Radiance's (docs/ambient.md):",
        "",
    ]
    .join("\n");
    for (name, what) in [
        (
            "--amb-share-max F",
            "largest share reach, 1..4 (1: Radiance's rule; default 3)",
        ),
        (
            "--amb-as0-split F",
            "-as 0 super-samples this share of -ad, 0..0.9 (0: rpict's)",
        ),
        ("--amb-hessian on|off", "radii from the irradiance Hessian"),
        (
            "--amb-reach on|off",
            "a value's interpolation reach up to 2",
        ),
        (
            "--amb-gradients on|off",
            "extrapolate values with their gradients",
        ),
        (
            "--amb-gradient-radii on|off",
            "the gradient limits Hessian radii (off)",
        ),
        (
            "--amb-glow-sampling on|off",
            "glows beyond their radius sampled as sources",
        ),
        ("--amb-corral on|off", "the light-leak test"),
        (
            "--amb-shadow-reuse on|off",
            "shadow rays reused within sample footprints",
        ),
        (
            "--amb-shadow-trust N",
            "agreeing shadow rays before a footprint's cube answers (8)",
        ),
        (
            "--amb-hessian-cells N",
            "cells of the Hessian's mesh at most (256)",
        ),
        (
            "--amb-outlier-limit F",
            "a cell brings at most F x the others' sum (2; 0: none)",
        ),
        (
            "--amb-ss-own on|off",
            "a cell's own sample counts in its super-sampling share",
        ),
    ] {
        s.push_str(&format!("  {name:<28} {what}\n"));
    }
    s
}

/// Apply one rpict option at `words[0]` (not a scene file). Returns the words consumed, or a
/// finished command for `-defaults`/`-version`.
fn apply_rpict_option(
    o: &mut RpictOptions,
    words: &[String],
) -> Result<Result<usize, Command>, OptError> {
    if let Some(n) = o.picture.view.apply_option(words)? {
        return Ok(Ok(n));
    }
    if let Some(n) = o.params.apply_option(words)? {
        return Ok(Ok(n));
    }
    if let Some(n) = o.picture.apply_option(words)? {
        return Ok(Ok(n));
    }
    if let Some(n) = o.run.apply_option(words)? {
        return Ok(Ok(n));
    }
    let w = words[0].as_str();
    match w {
        "-version" | "--version" => Ok(Err(Command::PrintVersion)),
        "--help" | "-h" => Ok(Err(Command::PrintHelp)),
        "-defaults" | "-help" => Ok(Err(Command::PrintDefaults(Box::new(o.clone())))),
        "-z" => Err(unsupported(w, "depth buffer output is not implemented")),
        "-P" | "-PP" => Err(unsupported(
            w,
            "persistent server mode is not implemented; use -n for threads",
        )),
        "-r" | "-ro" => Err(unsupported(w, "picture recovery is not implemented")),
        "-f" => Err(unsupported(w, "function files are not supported")),
        "-features" => Err(unsupported(w, "feature queries are not implemented")),
        _ => Err(OptError::Unknown(w.to_string())),
    }
}

/// Parse tpict's arguments (without argv[0]): expands `@file`/`$VAR`, applies `-vf` files
/// in order (later view options override, like rpict), validates numbers and ranges,
/// rejects unknown options (the error names the option) and unsupported ones with a reason.
/// Options come first, then scene files (`-` is stdin; none given means stdin).
/// `-defaults`/`-help` and `-version` end parsing at once, like rpict.
pub fn parse_rpict_args(args: &[String]) -> Result<Command, OptError> {
    let words = expand_args(args)?;
    let mut o = RpictOptions::default();
    let mut i = 0;
    while i < words.len() {
        let w = &words[i];
        let is_option = w.len() > 1 && w.starts_with('-');
        if !is_option {
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
        match apply_rpict_option(&mut o, &words[i..])? {
            Ok(n) => i += n,
            Err(cmd) => return Ok(cmd),
        }
    }
    if o.scene_files.is_empty() {
        o.scene_files.push("-".to_string());
    }
    if o.run.sequence_start.is_some() && o.scene_files.iter().any(|s| s == "-") {
        return Err(OptError::BadValue {
            option: "-S".into(),
            reason: "views are read from stdin, so the scene cannot come from stdin".into(),
        });
    }
    o.picture.view.frame()?;
    Ok(Command::Render(Box::new(o)))
}

/// Options as command-line words that [`parse_rpict_args`] parses back to the same value
/// (scene files excluded).
pub fn to_args(opts: &RpictOptions) -> Vec<String> {
    let mut w = opts.picture.to_words();
    w.extend(opts.params.to_words());
    w.extend(opts.run.to_words());
    w
}

#[cfg(test)]
mod tests {

    #[test]
    fn help_names_every_tessera_option() {
        let h = help_text();
        for name in crate::ambient::settings::OPTION_NAMES {
            assert!(h.contains(name), "{name} missing from the help");
        }
        for name in [
            "--allow-commands",
            "--obj-material",
            "--max-primitives",
            "--stats",
            "--amb-log",
            "--amb-flush",
            "--amb-force",
            "--no-overture",
            "--same-seeds",
            "-ax START",
            "-n N",
        ] {
            assert!(h.contains(name), "{name} missing from the help");
        }
        let w = |s: &str| vec![s.to_string()];
        // Fits a terminal and keeps its columns: every line within 100 characters, every
        // option line indented under its heading.
        for line in h.lines() {
            assert!(line.chars().count() <= 100, "too long: {line}");
            assert!(!line.starts_with('-'), "not indented: {line}");
        }
        assert_eq!(parse_rpict_args(&w("--help")).unwrap(), Command::PrintHelp);
        assert_eq!(parse_rpict_args(&w("-h")).unwrap(), Command::PrintHelp);
        assert_eq!(
            parse_rpict_args(&w("--version")).unwrap(),
            Command::PrintVersion
        );
    }

    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn overture_runs_only_for_cached_ambient_and_can_be_turned_off() {
        let parse = |a: &str| match parse_rpict_args(&words(a)).unwrap() {
            Command::Render(o) => *o,
            c => panic!("{c:?}"),
        };
        let step = |a: &str| {
            let o = parse(a);
            o.picture.overture_step(&o.params)
        };
        assert_eq!(step("-ab 1 s.rad"), 4);
        assert_eq!(step("-ab 1 -ps 1 s.rad"), 1);
        assert_eq!(step("-ab 1 -ps 8 s.rad"), 8);
        // No cache: nothing to fill.
        assert_eq!(step("-ab 0 s.rad"), 0);
        assert_eq!(step("-ab 1 -aa 0 s.rad"), 0);
        assert_eq!(step("-ab 1 -aa 1e-7 s.rad"), 0);
        assert_eq!(step("-ab 1 -ad 0 s.rad"), 0);
        let off = parse("-ab 1 --no-overture s.rad");
        assert_eq!(off.picture.overture_step(&off.params), 0);
        // The option survives the round trip through words (job manifests, `-defaults`).
        let w = to_args(&off);
        assert!(w.contains(&"--no-overture".to_string()), "{w:?}");
        // A manifest written before the option existed reads as on.
        let mut json = serde_json::to_value(parse("-ab 1 s.rad").picture).unwrap();
        json.as_object_mut().unwrap().remove("overture");
        let back: PictureParams = serde_json::from_value(json).unwrap();
        assert!(back.overture);
    }
}
