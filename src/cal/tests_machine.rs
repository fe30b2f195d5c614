//! Unit tests of the run-time machine and the pure forms: values bit for bit against the
//! tree walker and the machine, and what is compiled inline.

use super::*;

/// [`Pure::eval_lanes`] at lanes `0..n` against [`Pure::eval_into`] at each lane alone:
/// the same values bit for bit, and a lane is refused exactly where the point alone is.
/// False when the form does not run in lanes (jumps, or too many nodes).
fn lanes_agree(
    p: &Pure,
    n: usize,
    chans: &[[f64; 27]; LANES],
    args: &[f64],
    (values, nvalues): (&[[f64; 3]; LANES], usize),
) -> bool {
    let input = LaneInputs {
        chans,
        values,
        nvalues,
    };
    let mut out = [[0.0; 3]; LANES];
    let mut ok = [false; LANES];
    if !p.eval_lanes(n, &input, args, 1, &mut out, &mut ok) {
        return false;
    }
    for l in 0..n {
        let mut alone = [0.0];
        let one = p
            .eval_into(&chans[l], args, &values[l][..nvalues], &mut alone)
            .map(|()| alone[0]);
        match one {
            Some(v) => assert!(
                ok[l] && out[l][0].to_bits() == v.to_bits(),
                "lane {l} of {n}: {} against {v}",
                out[l][0]
            ),
            None => assert!(!ok[l], "lane {l} of {n}: {} where alone refused", out[l][0]),
        }
    }
    true
}

/// Eight points around `chan`: lane `l` moves the point, the direction's z and `Rdot`.
fn around(chan: &[f64; 27], i: usize) -> [[f64; 27]; LANES] {
    std::array::from_fn(|l| {
        let mut c = *chan;
        let x = ((i * LANES + l) as f64 * 0.618).sin();
        c[2] = (c[2] + 0.3 * x).clamp(-1.2, 1.2);
        c[6] += x;
        c[7] -= 0.5 * x;
        c[10] = if l == 3 { 0.0 } else { c[10] + 0.2 * x };
        c
    })
}

/// The run-time machine (`vm`) against the tree walker on random expressions over
/// definitions that use every kind of node: lazy and function-name arguments, recursion,
/// `if`/`select`/`min`/`max`, `arg`, BRDF-free channels, and errors of every kind (fatal
/// ones compared by message). Values must agree bit for bit.
#[test]
fn run_time_machine_matches_the_tree_walker() {
    const DEFS: &str = "
        a = Px*2 - 1; b = a*a + Py; c : 3;
        f(x) = x*x - a; g(x, y) = if(x, y, -y); h(p, x) = p(x) + 1; k(p) = h(p, Pz);
        r(n) = if(n - .5, n*r(n-1), 1); s(x, y, z) = select(x, y, z, x + y);
        m(x) = min(x, a, b) + max(b, x); q(x) = x/(x - 1) + x^.5;
        bad1 = nothere + 1; bad2(x) = g(x); bad3 = f; deep(n) = deep(n + 1);
        t(x) = atan2(x, a) + noise3(x, a, b) + arg(1) + arg(0);
        u(x, y) = f(x) + g(y, -x); w(x) = u(-x, x*b) / m(x); e(x) = if(x, x, sqrt(x));
        l(x) = t(x) + 1; o(x) = u(x, Py) - e(-x) + bound(-1, x, 1) + Acos(x);
    ";
    let atoms = [
        "a", "b", "c", "Px", "Py", "Pz", "A1", "arg(2)", "0", "1", "2.5", "-.5",
    ];
    let calls1 = [
        "f", "r", "m", "q", "t", "sin", "sqrt", "log", "floor", "w", "e", "l", "o",
    ];
    let mut seed: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = |n: usize| -> usize {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    fn gen(
        next: &mut dyn FnMut(usize) -> usize,
        d: u32,
        atoms: &[&str],
        calls1: &[&str],
    ) -> String {
        if d == 0 || next(4) == 0 {
            return atoms[next(atoms.len())].to_string();
        }
        let mut sub = || gen(next, d - 1, atoms, calls1);
        let (x, y, z) = (sub(), sub(), sub());
        match next(14) {
            0 => format!("({x} + {y})"),
            1 => format!("({x} - {y})"),
            2 => format!("({x} * {y})"),
            3 => format!("({x} / {y})"),
            4 => format!("({x} ^ {y})"),
            5 => format!("-({x})"),
            6 => format!("{}({x})", calls1[next(calls1.len())]),
            7 => format!("g({x}, {y})"),
            8 => format!("h({}, {x})", ["f", "sin", "r", "q"][next(4)]),
            9 => format!("s({x}, {y}, {z})"),
            10 => format!("if({x}, {y}, {z})"),
            11 => format!("select({x}, {y}, {z})"),
            12 => format!("max({x}, {y}, {z})"),
            _ => [
                "bad1", "bad2(1)", "bad3", "deep(0)", "k(f)", "k(sqrt)", "min()",
            ][next(7)]
            .to_string(),
        }
    }
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(DEFS.as_bytes(), "defs", Ctx::GLOBAL).unwrap();
    let mut exprs = Vec::new();
    for i in 0..4000 {
        let text = gen(&mut next, 5, &atoms, &calls1);
        if let Ok(e) = b.expr(&text, Ctx::GLOBAL, &format!("case:{i}")) {
            exprs.push((text, e));
        }
    }
    assert!(exprs.len() > 2000, "only {} compiled", exprs.len());
    let prog = b.finish();
    let mut kinds = [0usize; 4];
    let mut pure = [0usize; 2];
    let mut jumps = 0;
    let mut laned = 0;
    for (i, (text, e)) in exprs.iter().enumerate() {
        let mut chan = [0.0; 27];
        chan[6] = (i as f64 * 0.37).sin() * 2.0;
        chan[7] = (i as f64 * 0.11).cos();
        chan[8] = i as f64 * 0.01 - 3.0;
        let env = Env {
            chan,
            args: &[0.75, -2.0],
            brdf: None,
        };
        let vm = prog.begin(&env).eval(*e);
        let tree = prog.begin(&env).eval_tree(*e);
        // The pure form, where there is one, gives the machine's value or leaves it to it.
        if let Some(p) = prog.pure_expr(*e) {
            pure[0] += 1;
            jumps += usize::from(p.has_jumps());
            let none = ([[0.0; 3]; LANES], 0);
            let n = 1 + i % LANES;
            laned += usize::from(lanes_agree(
                &p,
                n,
                &around(&env.chan, i),
                env.args,
                (&none.0, none.1),
            ));
            if let Some(v) = p.eval(&env.chan, env.args, &[]) {
                pure[1] += 1;
                assert!(
                    matches!(vm, Ok(x) if x.to_bits() == v.to_bits()),
                    "{text}: machine {vm:?}, pure {v}"
                );
            }
        }
        let same = match (&vm, &tree) {
            (Ok(x), Ok(y)) => x.to_bits() == y.to_bits(),
            (x, y) => x == y,
        };
        assert!(same, "{text}: machine {vm:?}, tree walker {tree:?}");
        kinds[match vm {
            Ok(_) => 0,
            Err(EvalError::Domain) => 1,
            Err(EvalError::Range) => 2,
            Err(EvalError::Fatal(_)) => 3,
        }] += 1;
    }
    // Every outcome occurs.
    assert!(kinds.iter().all(|&k| k > 10), "{kinds:?}");
    // Many expressions are pure, and most of those evaluate without the machine.
    assert!(
        pure[0] > 500 && pure[1] > 300,
        "{pure:?} of {}",
        exprs.len()
    );
    // Branches skipped by jumps (an `if` or `select` with a library call in a branch)
    // are among them.
    assert!(jumps > 100, "{jumps} pure forms with jumps");
    // Those without jumps ran in lanes too.
    assert!(laned > 300, "{laned} pure forms in lanes");
}

/// Functions called with values (a pattern's function of its data values): the pure form
/// of each gives the machine's value bit for bit, or leaves the call to the machine; those
/// that are not pure are refused, never evaluated differently.
#[test]
fn pure_functions_match_the_machine() {
    const DEFS: &str = "
        corr(v) = if(AC - .5, A1*v, v); flat(v) = corr(v) / Rdot;
        theta = Acos(Dz) / DEGREE; phi = mod(Atan2(-Dy, -Dx) / DEGREE, 360);
        phi2 = tri(phi, 180); two(x, y) = x*A2 + y^.5 + noise3(x, y, Dz);
        many(x) = max(x, -x, Px) - min(Py, x); rec(n) = if(n, rec(n - 1), 0);
        name(f, x) = f(x); pick(x) = select(x, 1, 2); bad(x) = nothere + x;
        miss(x, y) = x + y; v1 = Px*Px; shared(x) = sq(x) + sq(x*v1) + bound(0, x, 1);
    ";
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(DEFS.as_bytes(), "defs", Ctx::GLOBAL).unwrap();
    let f = |b: &mut CalBuilder, n: &str| b.func(n, Ctx::GLOBAL).unwrap();
    let pure_ones = [
        "corr", "flat", "two", "many", "shared", "miss", "sq", "Acos", "tri",
    ];
    let refused = ["rec", "name", "bad"];
    let fs: Vec<_> = pure_ones
        .iter()
        .chain(&refused)
        .map(|n| (*n, f(&mut b, n)))
        .collect();
    let exprs: Vec<_> = ["theta", "phi", "phi2", "Dz*A1"]
        .iter()
        .map(|t| b.expr(t, Ctx::GLOBAL, "case").unwrap())
        .collect();
    let prog = b.finish();
    for (n, fr) in &fs {
        assert_eq!(prog.pure_func(*fr).is_some(), pure_ones.contains(n), "{n}");
    }
    // With the arguments known, `corr` is `A1*v` (two steps: the value, the product; the
    // `if` and `arg` are gone), `flat` four (and `Rdot`, the quotient), and `theta`'s
    // `DEGREE` (PI/180) is a number either way.
    let steps = |n: &str, args: Option<&[f64]>| {
        let fr = fs.iter().find(|f| f.0 == n).unwrap().1;
        prog.pure_func_with(fr, args).unwrap().steps()
    };
    assert!(steps("corr", None) >= 4, "{}", steps("corr", None));
    assert_eq!(steps("corr", Some(&[2.0, 3.0])), 2);
    assert_eq!(steps("flat", Some(&[2.0, 3.0])), 4);
    assert_eq!(steps("corr", Some(&[])), 1);
    let theta = prog.pure_expr(exprs[0]).unwrap().steps();
    // Dz, the two differences and two `if`s of `bound`, `acos`, the quotient.
    assert_eq!(theta, 7, "theta takes {theta} steps");
    let (mut same, mut left, mut laned) = (0, 0, 0);
    for i in 0..3000 {
        let x = |k: f64| ((i as f64 + 1.0) * k).sin();
        let mut chan = [0.0; 27];
        let d = glam::DVec3::new(x(0.71), x(0.37), x(1.13) * 1.2).normalize_or_zero();
        chan[..3].copy_from_slice(&d.to_array());
        chan[6] = x(2.3) * 3.0;
        chan[7] = x(0.2);
        chan[10] = if i % 97 == 0 { 0.0 } else { x(0.9) };
        let args: &[f64] = match i % 3 {
            0 => &[],
            1 => &[2.77778],
            _ => &[0.5, 2.0, -1.0],
        };
        let env = Env {
            chan,
            args,
            brdf: None,
        };
        let vals = [x(0.05) * 4.0, x(0.013).abs() * 9.0];
        let lane_vals: [[f64; 3]; LANES] = std::array::from_fn(|l| {
            [
                vals[0] + l as f64 * 0.25,
                vals[1] * (1.0 - l as f64 * 0.3),
                0.0,
            ]
        });
        let mut check = |p: Option<crate::cal::Pure>, vm: Result<f64, EvalError>, what: &str| {
            let Some(p) = p else { return };
            let nv = if what == "miss" { 1 } else { 2 };
            laned += usize::from(lanes_agree(
                &p,
                1 + i % LANES,
                &around(&chan, i),
                args,
                (&lane_vals, nv),
            ));
            match p.eval(&chan, args, &vals[..nv]) {
                Some(v) => {
                    assert!(
                        matches!(vm, Ok(w) if w.to_bits() == v.to_bits()),
                        "{what} case {i}: machine {vm:?}, pure {v}"
                    );
                    same += 1;
                }
                None => left += 1,
            }
        };
        for (n, fr) in &fs {
            let nv = if *n == "miss" { 1 } else { 2 };
            let vm = prog.begin(&env).call(*fr, &vals[..nv]);
            check(prog.pure_func(*fr), vm.clone(), n);
            // Specialised to the arguments the evaluation passes: `arg(n)` and what
            // follows from it alone computed once (`corr`'s `if` takes one branch).
            check(prog.pure_func_with(*fr, Some(args)), vm, n);
        }
        for e in &exprs {
            let vm = prog.begin(&env).eval(*e);
            check(prog.pure_expr(*e), vm.clone(), "expr");
            check(prog.pure_exprs_with(&[*e], Some(args)), vm, "expr");
        }
    }
    // Nearly all evaluate purely; a missing argument, Rdot = 0 and the like go back.
    assert!(
        same > 60_000 && left > 200,
        "{same} pure, {left} left to the machine"
    );
    assert!(laned > 60_000, "{laned} evaluated in lanes");
}

/// Small functions called with short call-free arguments are compiled inline (no call at
/// run time), nested ones too, `arg()` (the primitive's arguments in any frame) included;
/// a body with a call it cannot inline, recursion, a wrong argument count or a long
/// argument keeps its call. Values and errors are checked
/// against the tree walker by `run_time_machine_matches_the_tree_walker`.
#[test]
fn small_functions_are_compiled_inline() {
    const DEFS: &str = "
        a = Px*2 - 1; f(x) = x*x - a; g(x, y) = if(x, y, -y); u(x, y) = f(x) + g(y, -x);
        t(x) = x + arg(1); l(x) = t(x) + 1; r(n) = if(n - .5, n*r(n-1), 1);
        c(v) = if(arg(0) - .5, arg(1)*v, v); fc(v) = c(v) / Rdot; k(x) = r(x) + 1;
    ";
    let mut b = CalBuilder::new(&[]).unwrap();
    b.load_text(DEFS.as_bytes(), "defs", Ctx::GLOBAL).unwrap();
    let cases = [
        ("Acos(Dz)", 0),
        ("u(Px, -Py)", 0),
        ("u(Px*a, Py/2)", 0),
        ("Atan2(-Dy, -Dx)", 0),
        ("t(Px)", 0),
        ("l(Px)", 0),
        ("fc(Px)", 0),
        ("k(Px)", 1),
        ("r(3)", 1),
        ("f(Px, Py)", 1),
        ("f(Px*Py*Pz)", 1),
        ("f(sin(Px))", 1),
    ];
    let ids: Vec<_> = cases
        .iter()
        .map(|(t, _)| b.expr(t, Ctx::GLOBAL, "inline").unwrap())
        .collect();
    let prog = b.finish();
    for ((text, calls), e) in cases.iter().zip(ids) {
        assert_eq!(prog.calls_in(e), *calls, "{text}");
    }
}
