//! Unit tests: the verified values, errors and precedence cases of §1.2–1.10 of the
//! format reference.

use super::*;

fn ev(stmts: &str, expr: &str) -> Result<f64, IcalcError> {
    icalc(stmts, expr, CalOptions::default())
}

fn val(stmts: &str, expr: &str) -> f64 {
    match ev(stmts, expr) {
        Ok(v) => v,
        Err(e) => panic!("{stmts} / {expr}: {e}"),
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-300) || (a - b).abs() <= tol
}

fn assert_val(stmts: &str, expr: &str, want: f64, tol: f64) {
    let got = val(stmts, expr);
    assert!(
        close(got, want, tol),
        "{stmts} / {expr} = {got}, want {want}"
    );
}

fn compile_err(stmts: &str, expr: &str) -> CalError {
    match ev(stmts, expr) {
        Err(IcalcError::Compile(e)) => e,
        other => panic!("{stmts} / {expr}: expected a compile error, got {other:?}"),
    }
}

fn eval_err(stmts: &str, expr: &str) -> EvalError {
    match ev(stmts, expr) {
        Err(IcalcError::Eval(e)) => e,
        other => panic!("{stmts} / {expr}: expected an evaluation error, got {other:?}"),
    }
}

#[test]
fn comments_and_numbers() {
    assert_val("", "3{comment {nested} still}+4", 7.0, 0.0);
    assert_val("", "5.+.5e1", 10.0, 0.0);
    assert_eq!(
        compile_err("", ".").message,
        "badly formed number in expression \".\""
    );
    assert!(compile_err("x = 1.e;", "x")
        .message
        .contains("missing exponent"));
    assert!(compile_err("x = 3 {", "x").message.contains("'}' expected"));
    assert_val("a.b = 2; un2`P. = 3;", "a.b*un2`P.", 6.0, 0.0);
}

#[test]
fn no_comparison_operators() {
    for bad in ["1<2", "!1", "5%2"] {
        assert!(matches!(ev("", bad), Err(IcalcError::Compile(_))), "{bad}");
        assert!(matches!(
            ev(&format!("x = {bad};"), "x"),
            Err(IcalcError::Compile(_))
        ));
    }
}

#[test]
fn precedence() {
    let cases = [
        ("-2^2", 4.0),
        ("-x^2", 9.0),
        ("2^3^2", 512.0),
        ("2^-2", 0.25),
        ("-2^-2", 0.25),
        ("2^3^-1", 1.25992105),
        ("2*-3", -6.0),
        ("2--3", 5.0),
        ("2-+3", -1.0),
        ("7/2*2", 7.0),
        ("1-2-3", -4.0),
    ];
    for (e, want) in cases {
        assert_val("x = 3;", e, want, 1e-8);
        // The same without folding (as icalc).
        let opts = CalOptions {
            fold: false,
            ..CalOptions::default()
        };
        let got = icalc("x = 3;", e, opts).unwrap();
        assert!(close(got, want, 1e-8), "{e} unfolded: {got}");
    }
    assert!(matches!(ev("", "--3"), Err(IcalcError::Compile(_))));
}

#[test]
fn error_messages_and_positions() {
    let e = compile_err("x = (1+2;", "x");
    assert_eq!((e.line, e.col, e.message.as_str()), (1, 9, "')' expected"));
    assert_eq!(e.to_string(), "<input>:1:9: ')' expected");
    let e = compile_err("x = 1\ny = 2;", "x");
    assert_eq!((e.line, e.col, e.message.as_str()), (2, 1, "';' expected"));
    assert_eq!(compile_err("x 3;", "x").message, "'=' or ':' expected");
    assert_eq!(compile_err("2 = 3;", "x").message, "illegal variable name");
    assert_eq!(
        compile_err("f(2) = 3;", "x").message,
        "illegal variable name"
    );
    assert_eq!(
        compile_err("f(a`b) = 3;", "x").message,
        "illegal variable name"
    );
    assert_eq!(
        compile_err("x = 3 + *4;", "x").message,
        "unexpected character"
    );
    assert_eq!(compile_err("$1 = 3;", "x").message, "illegal variable name");
    let e = compile_err("", "sin(x");
    assert_eq!(
        e.to_string(),
        "<expr>:1:6: ')' expected in expression \"sin(x\""
    );
}

#[test]
fn folding_errors() {
    let e = compile_err("w = Px/0;", "w");
    assert_eq!((e.col, e.message.as_str()), (9, "divide by zero constant"));
    let e = compile_err("w = 1/0 + Px;", "w");
    assert_eq!((e.col, e.message.as_str()), (9, "bad constant expression"));
    assert!(compile_err("v : Px;\nw = v+1;", "w")
        .message
        .starts_with("ray parameter used in constant expression"));
    assert!(compile_err("f(x) : x + Px;\nw = f(2);", "w")
        .message
        .starts_with("ray parameter used in constant expression"));
    assert!(compile_err("v : A1;", "v")
        .message
        .starts_with("arg() used in a constant"));
    assert!(compile_err("", "sqrt(-1)")
        .message
        .contains("bad constant expression"));
    // Not constant: evaluated at run time.
    let opts = CalOptions::default();
    let env = Env {
        args: &[2.0],
        ..Env::default()
    };
    assert_eq!(icalc_env("f(x) : x + 1;", "f(2)+Px", opts, &env), Ok(3.0));
    assert_eq!(icalc_env("w = k + Px; k : 10;", "w", opts, &env), Ok(10.0));
    assert_eq!(
        icalc_env("w = k + A1; k = 10; k : 20;", "w", opts, &env),
        Ok(22.0)
    );
    assert_eq!(icalc_env("", "Px^0 + 2", opts, &env), Ok(3.0));
    assert_eq!(icalc_env("", "0/Px", opts, &env), Ok(0.0));
    assert_eq!(icalc_env("", "0^Px", opts, &env), Ok(0.0));
    // Folded at load: rand and the math library are constant functions.
    let mut b = CalBuilder::new(&[]).unwrap();
    let e = b.expr("cos(PI*sqrt(2))", Ctx::GLOBAL, "t:1").unwrap();
    let p = b.finish();
    assert!(p.node_count() > 0);
    assert!(close(
        p.begin(&Env::default()).eval(e).unwrap(),
        -0.266255342,
        1e-8
    ));
}

#[test]
fn definitions_and_lazy_arguments() {
    assert_val("f(x) = x*2;", "f(3,4)", 6.0, 0.0);
    assert_val("", "if(1,2)", 2.0, 0.0);
    assert!(
        matches!(eval_err("", "if(Px-1,2)"), EvalError::Fatal(m) if m.starts_with("if(): too few arguments"))
    );
    // With constant arguments the call folds when compiled: the same error, at load.
    assert!(compile_err("", "if(-1,2)")
        .message
        .starts_with("if(): too few arguments"));
    assert!(
        matches!(eval_err("f(a,b) = b;", "f(1)"), EvalError::Fatal(m) if m.starts_with("f(): too few arguments"))
    );
    assert_val("g(a) = a(2)+1; sq2(x) = x*x;", "g(sq2)", 5.0, 0.0);
    assert_val(
        "h(p) = g(p); g(a) = a(2)+1; sq2(x) = x*x;",
        "h(sq2)",
        5.0,
        0.0,
    );
    assert_val("g(a) = a(0)+1;", "g(cos)", 2.0, 0.0);
    assert_val(
        "fib(n) = if(n-1.5, fib(n-1)+fib(n-2), 1);",
        "fib(20)",
        10946.0,
        0.0,
    );
    // Last definition wins; references compiled earlier see it.
    assert_val("x = 1; y = x*10; x = 2;", "y", 20.0, 0.0);
    assert_val("f(a) = 1; y = f(0); f(a) = a+5;", "y", 5.0, 0.0);
    // Parameters shadow variables.
    assert_val("a = 100; f(a) = a+1;", "f(1)", 2.0, 0.0);
    // if: c > 0 only.
    assert_val("", "if(0,1,2)", 2.0, 0.0);
    assert_val("", "if(1e-9,1,2)", 1.0, 0.0);
}

#[test]
fn recursion_limit_is_an_error() {
    let e = eval_err("f(n) = f(n+1)+1;", "f(0)");
    assert!(matches!(e, EvalError::Fatal(m) if m.contains("recursion too deep")));
    let e = eval_err("x = x + 1;", "x");
    assert!(matches!(e, EvalError::Fatal(m) if m.contains("recursion too deep")));
    // And in a thread with a small stack.
    let h = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(|| {
            let r = ev("f(n) = if(n, 1 + f(n-1)*1 + 0*(n+n*(n-n/2)), 0);", "f(1e9)");
            matches!(r, Err(IcalcError::Eval(EvalError::Fatal(_))))
        })
        .unwrap();
    assert!(h.join().unwrap());
}

#[test]
fn undefined_names_are_fatal() {
    let e = eval_err("y = 1 + nothere;", "y");
    assert!(
        matches!(&e, EvalError::Fatal(m) if m.starts_with("nothere: undefined variable") && m.contains("<input>:1")),
        "{e}"
    );
    let e = eval_err("", "nofunc(2)");
    assert!(
        matches!(&e, EvalError::Fatal(m) if m.starts_with("nofunc(): undefined function")),
        "{e}"
    );
    let e = eval_err("", "NxP");
    assert!(
        matches!(&e, EvalError::Fatal(m) if m.starts_with("NxP: undefined variable")),
        "{e}"
    );
    let e = eval_err("", "A2");
    assert!(
        matches!(&e, EvalError::Fatal(m) if m.starts_with("missing real argument 2")),
        "{e}"
    );
}

#[test]
fn runtime_errors() {
    let opts = CalOptions::default();
    let env = Env {
        chan: [0.0; 27],
        ..Env::default()
    };
    let run = |e: &str| icalc_env("", e, opts, &env);
    assert_eq!(run("1/Px"), Err(IcalcError::Eval(EvalError::Range)));
    assert_eq!(run("sqrt(Px-1)"), Err(IcalcError::Eval(EvalError::Domain)));
    assert_eq!(run("log(Px)"), Err(IcalcError::Eval(EvalError::Range)));
    assert_eq!(
        run("(Px-8)^(1/3)"),
        Err(IcalcError::Eval(EvalError::Domain))
    );
    assert_eq!(run("Px^-1"), Err(IcalcError::Eval(EvalError::Range)));
    assert_eq!(run("acos(Px+2)"), Err(IcalcError::Eval(EvalError::Domain)));
    assert_eq!(
        run("select(Px+5,1,2)"),
        Err(IcalcError::Eval(EvalError::Domain))
    );
    assert_eq!(
        run("select(Px-0.6,1,2)"),
        Err(IcalcError::Eval(EvalError::Domain))
    );
    assert_eq!(run("select(Px-0.4,1,2)"), Ok(2.0));
    assert_eq!(run("(Px-8)^3"), Ok(-512.0));
    assert_eq!(run("1e300*1e300+Px"), Ok(f64::INFINITY));
}

#[test]
fn verified_library_values() {
    let cases: &[(&str, f64)] = &[
        ("rand(0)", 0.954473516),
        ("rand(0.5)", 0.234347013),
        ("rand(1)", 0.35008306),
        ("floor(-1.5)", -2.0),
        ("ceil(-1.5)", -1.0),
        ("atan2(1,-1)", 2.35619449),
        ("select(0,10,20,30)", 3.0),
        ("select(3.6,10,20,30,40)", 40.0),
        ("select(1.4,7,8)", 7.0),
        ("select(1.6,7,8)", 8.0),
        ("if(0,1,2)", 2.0),
        ("if(1e-9,1,2)", 1.0),
        ("max(3,9,-2)", 9.0),
        ("min(3,9,-2)", -2.0),
        ("exp(1)", std::f64::consts::E),
        ("log10(1000)", 3.0),
        ("bound(0,1.5,1)", 1.0),
        ("frac(-1.25)", 0.75),
        ("mod(-1,3)", 2.0),
        ("tri(2.5,1)", 0.5),
        ("hermite(0,1,0,0,.25)", 0.15625),
        ("bezier(0,1,1,0,.5)", 0.75),
        ("bspline(0,1,2,3,.5)", 1.5),
        ("grey(1,1,1)", 1.0),
        ("Sqrt(-4)", 0.0),
        ("Acos(2)", 0.0),
        ("sgn(-0.2)", -1.0),
        ("unif2norm(.975)", 1.96039492),
        ("nrand(3)", -0.471869794),
        ("dot(D1,D2)", 32.0),
        ("cross(1,D1,D2)", -3.0),
        ("noise3(0.5,0.25,0)", -0.0776367),
        ("noise3x(0.5,0.25,0)", -0.874999),
        ("fnoise3(0.5,0.25,0)", -0.3119419),
        ("noise3(1.3,2.7,0)", 0.155537),
        ("noise3x(1.3,2.7,0)", -0.924818),
        ("fnoise3(1.3,2.7,0)", -0.387185),
        ("noise3(-3.21,4.5,0)", 0.20397),
        ("noise3x(-3.21,4.5,0)", -0.207128),
        ("fnoise3(-3.21,4.5,0)", -0.044879),
    ];
    let defs = "D1(i) = select(i,1,2,3); D2(i) = select(i,4,5,6);";
    for (e, want) in cases {
        assert_val(defs, e, *want, 2e-6);
    }
}

#[test]
fn contexts() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("foo.cal"),
        "v = Px*2 + 3; w = v + k; k : 10;\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("bar.CAL"),
        "x = 1; early = gx; gx = 5; `loc = 7; glob` = 8; e`q = 9;\n",
    )
    .unwrap();
    let mut b = CalBuilder::new(&[dir.path().to_path_buf()]).unwrap();
    assert_eq!(b.rayinit(), "built-in");
    let foo = b.load_file("foo.cal").unwrap();
    assert_eq!(b.load_file("foo.cal").unwrap(), foo);
    let bar = b.load_file("bar.CAL").unwrap();
    let g = b.load_file(".").unwrap();
    assert_eq!(g, Ctx::GLOBAL);
    let ids = [
        b.expr("v", foo, "s:1").unwrap(),
        b.expr("w", foo, "s:2").unwrap(),
        b.expr("x", bar, "s:3").unwrap(),
        b.expr("early", bar, "s:4").unwrap(),
        b.expr("loc + glob", bar, "s:5").unwrap(),
        b.expr("e`q", bar, "s:6").unwrap(),
        b.expr("x`bar + glob` + v`foo", g, "s:7").unwrap(),
        b.expr("v`foo", g, "s:8").unwrap(),
        b.expr("x", g, "s:9").unwrap(),
    ];
    let prog = b.finish();
    let mut chan = [0.0; 27];
    chan[6] = 0.5;
    let env = Env {
        chan,
        ..Env::default()
    };
    let mut e = prog.begin(&env);
    let got: Vec<_> = ids.iter().map(|&i| e.eval(i)).collect();
    assert_eq!(got[0], Ok(4.0));
    assert_eq!(got[1], Ok(14.0));
    assert_eq!(got[2], Ok(1.0));
    assert_eq!(got[3], Ok(5.0));
    assert_eq!(got[4], Ok(15.0));
    assert_eq!(got[5], Ok(9.0));
    assert_eq!(got[6], Ok(13.0));
    assert_eq!(got[7], Ok(4.0));
    assert!(matches!(&got[8], Err(EvalError::Fatal(m)) if m.starts_with("x: undefined variable")));
}

#[test]
fn binding_happens_at_parse_time() {
    let dir = tempfile::tempdir().unwrap();
    // `y` references global x before the file defines its own x.
    std::fs::write(dir.path().join("late.cal"), "y = x; x = 2; z = x;\n").unwrap();
    let mut b = CalBuilder::new(&[dir.path().to_path_buf()]).unwrap();
    b.load_text(b"x = 1;", "g", Ctx::GLOBAL).unwrap();
    let c = b.load_file("late.cal").unwrap();
    let y = b.expr("y", c, "s:1").unwrap();
    let z = b.expr("z", c, "s:2").unwrap();
    let p = b.finish();
    let env = Env::default();
    let mut e = p.begin(&env);
    assert_eq!((e.eval(y), e.eval(z)), (Ok(1.0), Ok(2.0)));
}

#[test]
fn variables_are_cached_per_evaluation() {
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(b"v = Px * 2;", "t", Ctx::GLOBAL).unwrap();
    let e = b.expr("v", Ctx::GLOBAL, "s:1").unwrap();
    let f = b.func("noop", Ctx::GLOBAL).unwrap();
    let p = b.finish();
    let mut chan = [0.0; 27];
    for i in 0..5 {
        chan[6] = i as f64;
        let env = Env {
            chan,
            ..Env::default()
        };
        let mut ev = p.begin(&env);
        assert_eq!(ev.eval(e), Ok(2.0 * i as f64));
        // A nested evaluation on the same thread with another ray.
        let env2 = Env {
            chan: [7.0; 27],
            ..Env::default()
        };
        assert_eq!(p.begin(&env2).eval(e), Ok(14.0));
        assert_eq!(ev.eval(e), Ok(2.0 * i as f64));
        assert_eq!(ev.call(f, &[3.5]), Ok(3.5));
    }
}

#[test]
fn arg_and_brdf() {
    let mut b = CalBuilder::new(&[]).unwrap();
    let ids: Vec<_> = ["AC", "A1+A3", "arg(0.4)", "arg(2)", "NxP+CbP", "Idz"]
        .iter()
        .map(|t| b.expr(t, Ctx::GLOBAL, "s:1").unwrap())
        .collect();
    let p = b.finish();
    let env = Env {
        chan: [0.0; 27],
        args: &[1.0, 2.0, 3.0],
        brdf: Some([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]),
    };
    let mut e = p.begin(&env);
    let got: Vec<_> = ids.iter().map(|&i| e.eval(i).unwrap()).collect();
    assert_eq!(got, vec![3.0, 4.0, 3.0, 2.0, 8.0, 4.0]);
}

#[test]
fn rcalc_dialect() {
    let opts = CalOptions {
        dialect: Dialect::Rcalc,
        fold: false,
        rayinit: false,
    };
    let mut b = CalBuilder::with_options(&[], opts).unwrap();
    b.load_text(b"$1 = $2 * 2; $3 = 1/0;", "r", Ctx::GLOBAL)
        .unwrap();
    let outs = b.outputs().to_vec();
    let p = b.finish();
    let mut chan = [0.0; 27];
    chan[1] = 4.0;
    let env = Env {
        chan,
        ..Env::default()
    };
    let mut e = p.begin(&env);
    assert_eq!(outs[0].0, 1);
    assert_eq!(e.eval(outs[0].1), Ok(8.0));
    assert_eq!(e.eval(outs[1].1), Err(EvalError::Range));
    // Plain: no channels.
    let plain = CalOptions {
        dialect: Dialect::Plain,
        ..opts
    };
    assert!(icalc("", "$1", plain).is_err());
    assert!(icalc("", "noise3(1,2,3)", plain).is_err());
}

#[test]
fn warnings() {
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(
        b"x = 1; x = 2; c : 1; c : 2; sin(x) = x; k : Px;",
        "w",
        Ctx::GLOBAL,
    )
    .unwrap();
    let w = b.warnings().join("\n");
    assert!(w.contains("x: redefined"), "{w}");
    assert!(w.contains("c: constant redefined"), "{w}");
    assert!(w.contains("sin: definition hides library function"), "{w}");
    assert!(w.contains("k: assigned non-constant value"), "{w}");
}

#[test]
fn program_is_send_sync() {
    fn check<T: Send + Sync>() {}
    check::<Program>();
}

#[test]
fn channels_and_their_names() {
    let mut chan = [0.0; 27];
    chan[6] = 0.5;
    chan[7] = 0.25;
    let env = Env {
        chan,
        ..Env::default()
    };
    let opts = CalOptions::default();
    assert_eq!(
        icalc_env("", "$7+1 + ($8+1)*10 + ($9+1)*100", opts, &env),
        Ok(114.0)
    );
    assert_eq!(icalc_env("", "Px + Py*10 + Pz*100", opts, &env), Ok(3.0));
    assert!(matches!(
        icalc_env("", "$28", opts, &env),
        Err(IcalcError::Eval(EvalError::Fatal(m))) if m.starts_with("illegal channel number $28")
    ));
}

#[test]
fn many_threads_share_one_program() {
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(b"v = Px*Px; f(x) = v + x;", "t", Ctx::GLOBAL)
        .unwrap();
    let e = b
        .expr("f(Py) + noise3(Px, Py, 0)", Ctx::GLOBAL, "s:1")
        .unwrap();
    let p = b.finish();
    let handles: Vec<_> = (0..4)
        .map(|t| {
            let p = p.clone();
            std::thread::spawn(move || {
                (0..1000).all(|i| {
                    let mut chan = [0.0; 27];
                    chan[6] = (t * 1000 + i) as f64 * 0.01;
                    chan[7] = 1.0;
                    let env = Env {
                        chan,
                        ..Env::default()
                    };
                    let want = chan[6] * chan[6] + 1.0 + noise3(chan[6], 1.0, 0.0);
                    let ok = p.begin(&env).eval(e) == Ok(want);
                    ok
                })
            })
        })
        .collect();
    assert!(handles.into_iter().all(|h| h.join().unwrap()));
}
