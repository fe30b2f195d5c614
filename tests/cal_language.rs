//! The function language against real Radiance (rcalc, rtrace) and a reference evaluator:
//! thousands of random expressions, every library `.cal` file, Tessera's rayinit against
//! Radiance's, and property tests (the parser never panics; evaluation matches the
//! reference).

mod cal_gen;
mod common;

use cal_gen::{out_of, print, same, Gen, Out, Ref, Rng, E};
use common::{radiance, radiance_bin};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use tessera::cal::{CalBuilder, CalOptions, Ctx, Dialect, Env};

/// Library files with `$N = …` statements: rcalc scripts.
const RCALC_FILES: [&str; 6] = [
    "conv1.cal",
    "fitSH.cal",
    "uniq_rgb.cal",
    "view360stereo.cal",
    "vwparab.cal",
    "vwplanis.cal",
];

/// Library files whose constants (`:`) use names the host program or its command line
/// defines (pcomb's `xmax`, `-e 'MF:4'`, …): like Radiance, folding them without those
/// definitions is a fatal error, so they are compiled without folding (as icalc loads
/// files). rcalc scripts among them keep the rcalc dialect.
const HOST_FILES: [&str; 16] = [
    "clouds.cal",
    "ferwerda.cal",
    "filt.cal",
    "fisheye_corr.cal",
    "fovsample.cal",
    "peerless.cal",
    "reinhard.cal",
    "reinhart.cal",
    "reinsrc.cal",
    "rskysrc.cal",
    "screen.cal",
    "sphsamp.cal",
    "tumblin.cal",
    "uniq_rgb.cal",
    "vwparab.cal",
    "vwplanis.cal",
];

fn lib_dir(bin: &Path) -> PathBuf {
    bin.parent().unwrap().join("lib")
}

fn plain_nofold() -> CalOptions {
    CalOptions {
        dialect: Dialect::Plain,
        fold: false,
        rayinit: false,
    }
}

/// Tessera's outcomes for expressions (each in its own evaluation).
fn tessera_eval(
    defs: &str,
    texts: &[String],
    opts: CalOptions,
    env: &Env,
) -> Vec<Result<f64, Out>> {
    let mut b = CalBuilder::with_options(&[], opts).unwrap();
    b.load_text(defs.as_bytes(), "defs", Ctx::GLOBAL).unwrap();
    let ids: Vec<_> = texts
        .iter()
        .enumerate()
        .map(|(i, t)| b.expr(t, Ctx::GLOBAL, &format!("gen:{i}")).unwrap())
        .collect();
    let prog = b.finish();
    ids.iter()
        .map(|&e| out_of(prog.begin(env).eval(e)))
        .collect()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Run rcalc on `$1..$N` outputs; returns the values.
fn rcalc_batch(bin: &Path, defs: &str, texts: &[String]) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let mut src = String::from(defs);
    for (i, t) in texts.iter().enumerate() {
        src.push_str(&format!("${} = {t};\n", i + 1));
    }
    let f = dir.path().join("batch.cal");
    std::fs::write(&f, src).unwrap();
    let out = radiance(bin, "rcalc")
        .args(["-n", "-od", "-f"])
        .arg(&f)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rcalc: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Vec<f64> = out
        .stdout
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(v.len(), texts.len());
    v
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn random_expressions_match_rcalc() {
    let Some(bin) = radiance_bin() else { return };
    let gen = Gen { noise: false };
    let (mut finite, mut nonfinite, mut err_nan, mut err_masked, mut skipped) = (0, 0, 0, 0, 0);
    let mut bad = Vec::new();
    for batch in 0..3u64 {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ ((batch + 1) * 0x1234_5678));
        let mut exprs: Vec<E> = Vec::new();
        let mut want = Vec::new();
        while exprs.len() < 1000 {
            let depth = 1 + rng.below(6) as u32;
            let e = gen.expr(&mut rng, depth);
            let mut r = Ref::new();
            let w = r.eval(&e);
            if r.unsafe_6a {
                skipped += 1;
                continue;
            }
            exprs.push(e);
            want.push(w);
        }
        let texts: Vec<String> = exprs.iter().map(|e| print(e, false)).collect();
        let ours = tessera_eval(cal_gen::DEFS, &texts, plain_nofold(), &Env::default());
        let theirs = rcalc_batch(&bin, cal_gen::DEFS, &texts);
        for i in 0..texts.len() {
            if !same(ours[i], want[i]) {
                bad.push(format!(
                    "{}: tessera {:?}, reference {:?}",
                    texts[i], ours[i], want[i]
                ));
            }
            let r = theirs[i];
            match want[i] {
                Ok(v) if v.is_finite() => {
                    if close(v, r, 1e-9) {
                        finite += 1;
                    } else {
                        bad.push(format!("{}: reference {v:e}, rcalc {r:e}", texts[i]));
                    }
                }
                Ok(v) => {
                    if same(Ok(v), Ok(r)) {
                        nonfinite += 1;
                    } else {
                        bad.push(format!("{}: reference {v:e}, rcalc {r:e}", texts[i]));
                    }
                }
                // 6.0a detects nothing: NaN/Inf where master reports an error, or a finite
                // value where it replaced a division by zero with 0 or an error with 0.
                Err(_) if !r.is_finite() => err_nan += 1,
                Err(_) => err_masked += 1,
            }
        }
    }
    eprintln!(
        "rcalc agreement: {finite} finite equal, {nonfinite} non-finite equal, \
         {err_nan} errors (6.0a NaN/Inf), {err_masked} errors (6.0a masked), \
         {skipped} skipped (6.0a select crash)"
    );
    assert!(
        bad.is_empty(),
        "{} mismatches:\n{}",
        bad.len(),
        bad[..bad.len().min(20)].join("\n")
    );
    assert!(finite > 1500, "too few finite comparisons: {finite}");
}

/// rtrace over a glow plane with a brightfunc whose value is expression i at x = i + 0.5.
fn rtrace_batch(bin: &Path, dir: &Path, cal: &str, n: usize) -> Vec<f32> {
    std::fs::write(dir.join("t.cal"), cal).unwrap();
    let scene = format!(
        "void brightfunc bf\n2 v t.cal\n0\n0\nbf glow g\n0\n0\n4 1 1 1 0\n\
         g polygon p\n0\n0\n12 -1 -1 0 {n}.5 -1 0 {n}.5 2 0 -1 2 0\n"
    );
    std::fs::write(dir.join("s.rad"), scene).unwrap();
    let oct = radiance(bin, "oconv")
        .current_dir(dir)
        .arg("s.rad")
        .output()
        .unwrap();
    assert!(
        oct.status.success(),
        "oconv: {}",
        String::from_utf8_lossy(&oct.stderr)
    );
    std::fs::write(dir.join("s.oct"), &oct.stdout).unwrap();
    let rays: String = (0..n).map(|i| format!("{}.5 0.5 1 0 0 -1\n", i)).collect();
    std::fs::write(dir.join("rays.txt"), rays).unwrap();
    let lib = lib_dir(bin);
    let out = radiance(bin, "rtrace")
        .current_dir(dir)
        .env("RAYPATH", format!(".:{}", lib.display()))
        .args(["-h", "-faf", "-ov", "s.oct"])
        .stdin(std::fs::File::open(dir.join("rays.txt")).unwrap())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rtrace: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Vec<f32> = out
        .stdout
        .chunks_exact(12)
        .map(|c| f32::from_le_bytes(c[..4].try_into().unwrap()))
        .collect();
    assert_eq!(v.len(), n);
    v
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn random_noise_expressions_match_rtrace() {
    let Some(bin) = radiance_bin() else { return };
    let gen = Gen { noise: true };
    let dir = tempfile::tempdir().unwrap();
    let n = 1500;
    let mut rng = Rng(0x5151_2024);
    let (mut exprs, mut want) = (Vec::new(), Vec::new());
    while exprs.len() < n {
        let depth = 1 + rng.below(5) as u32;
        let e = gen.expr(&mut rng, depth);
        let mut r = Ref::new();
        let w = r.eval(&e);
        if !r.unsafe_6a {
            exprs.push(e);
            want.push(w);
        }
    }
    let mut cal = format!("{}z0 = Py - .5;\n", cal_gen::DEFS);
    for (i, e) in exprs.iter().enumerate() {
        cal.push_str(&format!("e{} = {};\n", i + 1, print(e, true)));
    }
    cal.push_str("v = select(floor(Px)+1");
    for i in 0..n {
        cal.push_str(&format!(",\n e{}", i + 1));
    }
    cal.push_str(");\n");
    let theirs = rtrace_batch(&bin, dir.path(), &cal, n);
    // Tessera, with Radiance's rayinit.cal as rtrace has it.
    let mut b = CalBuilder::new(&[dir.path().to_path_buf(), lib_dir(&bin)]).unwrap();
    assert!(b.rayinit().ends_with("rayinit.cal"), "{}", b.rayinit());
    let ctx = b.load_file("t.cal").unwrap();
    let v = b.expr("v", ctx, "s.rad:1").unwrap();
    let prog = b.finish();
    let (mut agree, mut errors, mut unstable) = (0, 0, 0);
    let mut bad = Vec::new();
    for i in 0..n {
        let mut chan = [0.0; 27];
        chan[6] = i as f64 + 0.5;
        chan[7] = 0.5;
        let env = Env {
            chan,
            ..Env::default()
        };
        let ours = out_of(prog.begin(&env).eval(v));
        let text = print(&exprs[i], false);
        if !same(ours, want[i]) {
            bad.push(format!("{text}: tessera {ours:?}, reference {:?}", want[i]));
        }
        // Expressions that amplify the last bits of a noise value (cancellations in
        // noise3x, huge coordinates) are not comparable.
        let mut r = Ref {
            perturb: 1e-12,
            ..Ref::new()
        };
        let stable = match (want[i], r.eval(&exprs[i])) {
            (Ok(a), Ok(b)) => (a - b).abs() <= 1e-8 * a.abs() + 1e-30,
            (a, b) => a == b,
        };
        match want[i] {
            _ if !stable => unstable += 1,
            Ok(w) if w.is_finite() && (w == 0.0 || (1e-30..1e30).contains(&w.abs())) => {
                let r = theirs[i] as f64;
                if (r - w).abs() <= 1e-6 * w.abs() + 1e-30 {
                    agree += 1;
                } else {
                    bad.push(format!("{text}: reference {w:e}, rtrace {r:e}"));
                }
            }
            Ok(_) => {}
            Err(_) => errors += 1,
        }
    }
    eprintln!(
        "rtrace agreement: {agree} equal (float precision), {errors} errors and {unstable} \
         ill-conditioned not compared"
    );
    assert!(
        bad.is_empty(),
        "{} mismatches:\n{}",
        bad.len(),
        bad[..bad.len().min(20)].join("\n")
    );
    assert!(agree > 800, "too few comparisons: {agree}");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn every_library_file_compiles() {
    let Some(bin) = radiance_bin() else { return };
    let lib = lib_dir(&bin);
    let mut files: Vec<String> = std::fs::read_dir(&lib)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".cal"))
        .collect();
    files.sort();
    let mut failed = Vec::new();
    for f in &files {
        let rcalc = RCALC_FILES.contains(&f.as_str());
        let host = HOST_FILES.contains(&f.as_str());
        let opts = CalOptions {
            dialect: if rcalc {
                Dialect::Rcalc
            } else {
                Dialect::Renderer
            },
            fold: !host,
            rayinit: true,
        };
        let mut b = CalBuilder::with_options(std::slice::from_ref(&lib), opts).unwrap();
        if let Err(e) = b.load_file(f) {
            failed.push(e.to_string());
        }
        // In the wrong dialect, a file with `$N =` does not compile; nor does a host file
        // folded without its host's definitions.
        if rcalc != host {
            let opts = CalOptions {
                dialect: if rcalc {
                    Dialect::Renderer
                } else {
                    Dialect::Rcalc
                },
                fold: host,
                rayinit: true,
            };
            let mut b = CalBuilder::with_options(std::slice::from_ref(&lib), opts).unwrap();
            assert!(b.load_file(f).is_err(), "{f} compiles in the wrong dialect");
        }
    }
    eprintln!(
        "{} library files compiled ({} as rcalc scripts, {} without folding)",
        files.len(),
        RCALC_FILES.len(),
        HOST_FILES.len()
    );
    assert!(files.len() > 100, "{} files", files.len());
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// rayinit functions and their number of arguments.
const RAYINIT_FUNCS: [(&str, usize); 31] = [
    ("bound", 3),
    ("Acos", 1),
    ("Asin", 1),
    ("Atan2", 2),
    ("Exp", 1),
    ("Sqrt", 1),
    ("and", 2),
    ("or", 2),
    ("not", 1),
    ("xor", 2),
    ("abs", 1),
    ("sgn", 1),
    ("sq", 1),
    ("inside", 3),
    ("frac", 1),
    ("mod", 2),
    ("tri", 2),
    ("linterp", 3),
    ("noop", 1),
    ("clip", 1),
    ("noneg", 1),
    ("red", 3),
    ("green", 3),
    ("blue", 3),
    ("grey", 3),
    ("clip_r", 3),
    ("clipgrey", 3),
    ("fade", 3),
    ("hermite", 5),
    ("bezier", 5),
    ("bspline", 5),
];

fn rayinit_prelude() -> String {
    let mut prelude = String::new();
    for (i, n) in tessera::cal::CHANNELS.iter().enumerate() {
        prelude.push_str(&format!("{n} = ${};\n", i + 1));
    }
    for (i, n) in tessera::cal::BRDF_VARS.iter().enumerate() {
        prelude.push_str(&format!("{n} = ${};\n", i + 28));
    }
    prelude.push_str("arg(n) = select(n, $35, $36, $37, $38, $39, $40);\n");
    prelude
}

/// Calls of every rayinit function with random arguments, and the names that use rays.
fn rayinit_texts(rng: &mut Rng) -> Vec<String> {
    let mut texts: Vec<String> = Vec::new();
    for _ in 0..12 {
        for (f, n) in RAYINIT_FUNCS {
            let args: Vec<String> = (0..n)
                .map(|_| {
                    format!(
                        "{:.6}",
                        (rng.unit() - 0.5) * [2.0, 6.0, 300.0][rng.below(3)]
                    )
                })
                .collect();
            texts.push(format!("{f}({})", args.join(",")));
        }
        texts.push(format!("unif2norm({:.6})", 0.001 + 0.998 * rng.unit()));
        texts.push(format!("nrand({:.4})", rng.unit() * 100.0));
    }
    for t in [
        "PI",
        "DEGREE",
        "FTINY",
        "AC",
        "A1",
        "A4",
        "D(1)+D(2)*10+D(3)*100",
        "N(2)",
        "P(3)",
        "dot(D,N)",
        "cross(1,D,P)",
        "cross(2,D,P)",
        "cross(3,D,P)",
        "U",
        "V",
        "Idx",
        "Idy",
        "Idz",
        "Ldx(.3,.4,.5)",
        "Ldy(.3,.4,.5)",
        "Ldz(.3,.4,.5)",
    ] {
        texts.push(t.to_string());
    }
    texts
}

/// Input rows: a unit direction, a unit normal, a point, …; a perturbed normal; 6 real
/// arguments.
fn rayinit_inputs(rng: &mut Rng) -> Vec<Vec<f64>> {
    let unit = |r: &mut Rng| {
        let v: [f64; 3] = [r.unit() - 0.5, r.unit() - 0.5, r.unit() - 0.5];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / l)
    };
    let mut input = Vec::new();
    for _ in 0..3 {
        let mut row: Vec<f64> = Vec::new();
        row.extend(unit(rng));
        row.extend(unit(rng));
        row.extend((0..21).map(|_| (rng.unit() - 0.5) * 4.0));
        row.extend(unit(rng));
        row.extend((0..4).map(|_| rng.unit()));
        row.extend((0..6).map(|_| (rng.unit() - 0.5) * 4.0));
        input.push(row);
    }
    input
}

/// rcalc's values of `texts` for each input row, with Radiance's rayinit.cal.
fn rayinit_rcalc(bin: &Path, prelude: &str, texts: &[String], input: &[Vec<f64>]) -> Vec<f64> {
    let dir = tempfile::tempdir().unwrap();
    let mut src = prelude.to_string();
    for (i, t) in texts.iter().enumerate() {
        src.push_str(&format!("${} = {t};\n", i + 1));
    }
    std::fs::write(dir.path().join("p.cal"), src).unwrap();
    let mut inp = String::new();
    for row in input {
        let s: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
        inp.push_str(&(s.join(" ") + "\n"));
    }
    std::fs::write(dir.path().join("in.txt"), inp).unwrap();
    let out = radiance(bin, "rcalc")
        .args(["-od", "-f", "rayinit.cal", "-f"])
        .arg(dir.path().join("p.cal"))
        .stdin(std::fs::File::open(dir.path().join("in.txt")).unwrap())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rcalc: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let theirs: Vec<f64> = out
        .stdout
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(theirs.len(), texts.len() * input.len());
    theirs
}

/// Tessera's built-in rayinit.cal against Radiance's, through rcalc with the ray channels,
/// BRDF variables and real arguments given as input fields.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn builtin_rayinit_matches_radiance() {
    let Some(bin) = radiance_bin() else { return };
    let mut rng = Rng(77);
    let prelude = rayinit_prelude();
    let texts = rayinit_texts(&mut rng);
    let input = rayinit_inputs(&mut rng);
    let theirs = rayinit_rcalc(&bin, &prelude, &texts, &input);
    // Tessera: built-in rayinit (empty RAYPATH).
    let mut b = CalBuilder::new(&[]).unwrap();
    assert_eq!(b.rayinit(), "built-in");
    let ids: Vec<_> = texts
        .iter()
        .map(|t| b.expr(t, Ctx::GLOBAL, "t:1").unwrap())
        .collect();
    let prog = b.finish();
    let mut bad = Vec::new();
    for (r, row) in input.iter().enumerate() {
        let env = Env {
            chan: row[..27].try_into().unwrap(),
            args: &row[34..40],
            brdf: Some(row[27..34].try_into().unwrap()),
        };
        let mut ev = prog.begin(&env);
        for (i, &e) in ids.iter().enumerate() {
            let want = theirs[r * texts.len() + i];
            match ev.eval(e) {
                Ok(v) if close(v, want, 1e-9) || (v - want).abs() < 1e-12 => {}
                got => bad.push(format!(
                    "{} (row {r}): tessera {got:?}, radiance {want:e}",
                    texts[i]
                )),
            }
        }
    }
    eprintln!("rayinit: {} comparisons", texts.len() * input.len());
    assert!(
        bad.is_empty(),
        "{} mismatches:\n{}",
        bad.len(),
        bad[..bad.len().min(30)].join("\n")
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, .. ProptestConfig::default() })]

    /// Whatever the text, compiling (and evaluating what compiles) returns.
    #[test]
    fn parser_never_panics(text in "\\PC{0,60}", bytes in proptest::collection::vec(any::<u8>(), 0..80)) {
        for t in [text.as_bytes(), &bytes[..]] {
            let mut b = CalBuilder::new(&[]).unwrap();
            let _ = b.load_text(t, "p", Ctx::GLOBAL);
            let s = String::from_utf8_lossy(t);
            let e = b.expr(&s, Ctx::GLOBAL, "p:1");
            let prog = b.finish();
            if let Ok(e) = e {
                let _ = prog.begin(&Env::default()).eval(e);
            }
        }
    }

    /// Grammar-shaped noise: tokens of the language in random order.
    #[test]
    fn token_soup_never_panics(toks in proptest::collection::vec(0usize..24, 0..40)) {
        const T: [&str; 24] = ["x", "f", "(", ")", ",", ";", "=", ":", "+", "-", "*", "/", "^",
            "1", ".5", "2e3", "$1", "`c", "x`", "if", "select", "{", "}", "\n"];
        let text: String = toks.iter().map(|&i| T[i]).collect::<Vec<_>>().join(" ");
        let mut b = CalBuilder::new(&[]).unwrap();
        let _ = b.load_text(text.as_bytes(), "p", Ctx::GLOBAL);
        let _ = b.expr(&text, Ctx::GLOBAL, "p:1");
        let _ = b.finish();
    }

    /// Random valid expressions evaluate as the reference evaluator says (no folding),
    /// and folding does not change finite results beyond rounding (without literal zeros:
    /// folding makes `0*x` +0 whatever the sign of x, as Radiance; without noise calls,
    /// whose high octaves turn a last-bit difference of an argument into a visible one:
    /// `fnoise3(1.625, a / 8.75, 3187500)` differs by 0.0016 when `a / 8.75` is folded into
    /// `a * (1 / 8.75)`; without sin, cos, tan and rand, for the same reason, rand
    /// everywhere and the others far from the origin:
    /// `4.81 / sin(rand(1.125) ^ (c + b ^ 9) / atan2(7.94, .5558))`, at about `sin(2.3e63)`,
    /// gave −57.8 folded against −12.3).
    #[test]
    fn evaluation_matches_reference(seed in any::<u64>(), depth in 1u32..7) {
        let mut rng = Rng(seed | 1);
        let e = Gen { noise: true }.expr(&mut rng, depth);
        let text = print(&e, false);
        let want = Ref::new().eval(&e);
        let opts = CalOptions { dialect: Dialect::Renderer, fold: false, rayinit: false };
        let got = tessera_eval(cal_gen::DEFS, std::slice::from_ref(&text), opts, &Env::default())[0];
        prop_assert!(same(got, want), "{}: {:?} vs {:?}", text, got, want);
        let folded = tessera::cal::icalc(cal_gen::DEFS, &text, CalOptions { rayinit: false, ..CalOptions::default() });
        let unstable = cal_gen::has_zero(&e) || cal_gen::has_noise(&e) || cal_gen::has_periodic(&e);
        if let (Ok(w), Ok(f), false) = (want, &folded, unstable) {
            prop_assert!(!w.is_finite() || close(*f, w, 1e-6) || (f - w).abs() < 1e-9,
                "{}: folded {} vs {}", text, f, w);
        }
    }
}

/// The noise functions at random points against rtrace (float output).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn noise_functions_match_rtrace() {
    let Some(bin) = radiance_bin() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng(4242);
    // The turbulence functions come from rayinit (Tessera's built-in one here, Radiance's
    // in rtrace); their fourth argument is the finest scale.
    let funcs = [
        "noise3",
        "noise3x",
        "noise3y",
        "noise3z",
        "fnoise3",
        "turbulence",
        "turbulencex",
        "turbulencey",
    ];
    let n = 1000;
    let mut pts = Vec::new();
    let mut cal = String::from("z0 = Py - .5;\n");
    for i in 0..n {
        let scale = [1.0, 10.0, 200.0, 1e5][rng.below(4)];
        let p: [f64; 3] = [0, 1, 2].map(|_| ((rng.unit() - 0.5) * scale * 1e6).round() / 1e6);
        let f = funcs[i % funcs.len()];
        let sc = if f.starts_with("turb") { ", .01" } else { "" };
        cal.push_str(&format!(
            "e{} = {f}({:e}+z0, {:e}+z0, {:e}+z0{sc});\n",
            i + 1,
            p[0],
            p[1],
            p[2]
        ));
        pts.push((f, p));
    }
    cal.push_str("v = select(floor(Px)+1");
    for i in 0..n {
        cal.push_str(&format!(",\n e{}", i + 1));
    }
    cal.push_str(");\n");
    let theirs = rtrace_batch(&bin, dir.path(), &cal, n);
    let mut worst = [0f64; 8];
    let mut bad = Vec::new();
    for (i, (f, p)) in pts.iter().enumerate() {
        let sc = if f.starts_with("turb") { ", .01" } else { "" };
        let text = format!("{f}({:e},{:e},{:e}{sc})", p[0], p[1], p[2]);
        let ours = tessera::cal::icalc("", &text, CalOptions::default()).unwrap();
        let r = theirs[i] as f64;
        let err = (ours - r).abs() / ours.abs().max(1e-3);
        let k = funcs.iter().position(|x| x == f).unwrap();
        worst[k] = worst[k].max(err);
        if err > 1e-5 {
            bad.push(format!("{f}({:?}) = {ours:e}, rtrace {r:e}", p));
        }
    }
    eprintln!(
        "noise worst relative errors {:?}",
        funcs.iter().zip(worst).collect::<Vec<_>>()
    );
    assert!(
        bad.is_empty(),
        "{} mismatches:\n{}",
        bad.len(),
        bad[..bad.len().min(20)].join("\n")
    );
}
