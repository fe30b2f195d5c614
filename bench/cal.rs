//! ns per evaluation of typical pattern expressions (`cargo bench --bench cal`).
//!
//! Each evaluation is one [`Program::begin`] (a clock tick, as for one ray hitting one
//! modifier) and one [`Evaluation::eval`], with the ray direction and hit point changing
//! every time. With Radiance installed (`TESSERA_RADIANCE_BIN`, or its default location),
//! Radiance's own skybright.cal and source.cal (what ies2rad luminaires call) are measured
//! too. `cargo bench --bench cal -- WORD` runs the cases whose name contains WORD.
//!
//! The second column is the same expression's pure form ([`tessera::cal::Pure`], what
//! patterns evaluate first), with the same channels; "–" where the expression is not pure
//! (it calls a function recursively, or is too large).

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;
use tessera::cal::{CalBuilder, Env, ExprId, Program};

/// A clear sky as gensky describes it (format reference §8.1), written for this benchmark.
const SKY: &str = "
wmean(a,x,b,y) = (a*x + b*y)/(a + b);
cosgam = Dx*A5 + Dy*A6 + Dz*A7;
gamma = Acos(cosgam);
clear = A2*(.91 + 10*exp(-3*gamma) + .45*cosgam*cosgam)
	* if(Dz-.01, 1-exp(-.32/Dz), 1) / A4;
sky = wmean((Dz+1.01)^10, clear, (Dz+1.01)^-10, A3);
";

const ARGS: [f64; 7] = [1.0, 11.58, 23.74, 0.6922, 0.067850, -0.617254, 0.783832];

/// The channels of evaluation `i`: the ray direction and hit point change every time.
fn channels(i: usize) -> [f64; 27] {
    let a = i as f64 * 0.001;
    let mut chan = [0.0; 27];
    let (s, c) = a.sin_cos();
    chan[0] = 0.6 * c;
    chan[1] = 0.6 * s;
    chan[2] = 0.8;
    chan[6] = 3.0 * c + 0.1 * a;
    chan[7] = 2.0 * s;
    chan[8] = 0.5 * a;
    chan
}

/// ns per evaluation through the machine, and through the pure form if there is one.
fn time(name: &str, prog: &Program, e: ExprId, n: usize) -> (f64, Option<f64>) {
    let mut sum = 0.0;
    let t = Instant::now();
    for i in 0..n {
        let env = Env {
            chan: channels(i),
            args: &ARGS,
            brdf: None,
        };
        let mut ev = prog.begin(&env);
        sum += ev.eval(black_box(e)).unwrap_or(0.0);
    }
    let ns = t.elapsed().as_nanos() as f64 / n as f64;
    let pure = prog.pure_expr(e).map(|p| {
        let t = Instant::now();
        for i in 0..n {
            sum += black_box(&p).eval(&channels(i), &ARGS, &[]).unwrap_or(0.0);
        }
        t.elapsed().as_nanos() as f64 / n as f64
    });
    black_box(sum);
    let pure_txt = pure.map_or("–".to_string(), |p| format!("{p:.1}"));
    println!("{name:<44} {ns:>8.1} ns/eval   pure {pure_txt:>8} ns/eval");
    (ns, pure)
}

fn main() {
    let bin = std::env::var("TESSERA_RADIANCE_BIN")
        .unwrap_or_else(|_| "/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin".into());
    let lib = PathBuf::from(bin).parent().map(|p| p.join("lib")).unwrap();
    let raypath: Vec<PathBuf> = if lib.join("skybright.cal").is_file() {
        vec![lib.clone()]
    } else {
        Vec::new()
    };
    let mut b = CalBuilder::new(&raypath).unwrap();
    println!("rayinit: {}", b.rayinit());
    let sky = b.context("bench");
    b.load_text(SKY.as_bytes(), "sky", sky).unwrap();
    let g = tessera::cal::Ctx::GLOBAL;
    let cases: Vec<(&str, ExprId)> = vec![
        ("Px (one channel)", b.expr("Px", g, "b:0").unwrap()),
        (
            "Px*2 + Py (trivial)",
            b.expr("Px*2 + Py", g, "b:1").unwrap(),
        ),
        (
            "clear sky (gensky's formula)",
            b.expr("sky", sky, "b:2").unwrap(),
        ),
        (
            "noise3(Px,Py,Pz)",
            b.expr("noise3(Px,Py,Pz)", g, "b:3").unwrap(),
        ),
        (
            "fnoise3(Px,Py,Pz)",
            b.expr("fnoise3(Px,Py,Pz)", g, "b:4").unwrap(),
        ),
        (
            "marble: sin(Px*3 + 4*turbulence(P, .01))",
            b.expr("sin(Px*3 + 4*turbulence(Px,Py,Pz,.01))", g, "b:5")
                .unwrap(),
        ),
    ];
    let mut cases = cases;
    if !raypath.is_empty() {
        let ctx = b.load_file("skybright.cal").unwrap();
        cases.push((
            "skybr (Radiance's skybright.cal)",
            b.expr("skybr", ctx, "b:6").unwrap(),
        ));
        // An ies2rad luminaire's brightdata: the coordinate and the correction function
        // (without the data lookup between them).
        let src = b.load_file("source.cal").unwrap();
        cases.push((
            "src_theta (source.cal, ies2rad)",
            b.expr("src_theta", src, "b:7").unwrap(),
        ));
        cases.push((
            "flatcorr(2.5) (source.cal, ies2rad)",
            b.expr("flatcorr(2.5)", src, "b:8").unwrap(),
        ));
    }
    let prog = b.finish();
    let n = 2_000_000;
    // `cargo bench --bench cal -- WORD` runs the cases whose name contains WORD.
    let only = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    for (name, e) in cases {
        if only.as_deref().is_some_and(|w| !name.contains(w)) {
            continue;
        }
        time(name, &prog, e, n);
    }
}
