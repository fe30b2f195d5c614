//! Tests for tpict's (rpict's) command line: parsing, errors, `@file`/`$VAR` expansion,
//! `-vf`, `-defaults` text (checked against real rpict when installed) and round trips.

use std::process::Command as Proc;

use glam::DVec3;
use proptest::prelude::*;
use tessera::ambient::settings::AmbientSettings;
use tessera::options::{
    defaults_text, expand_args, parse_rpict_args, split_words, to_args, Command, OptError,
    PictureParams, RenderParams, RpictOptions, RunParams,
};
use tessera::view::{View, ViewType};

mod common;
use common::radiance_bin;

fn w(s: &str) -> Vec<String> {
    s.split_whitespace().map(String::from).collect()
}

fn render(s: &str) -> RpictOptions {
    match parse_rpict_args(&w(s)) {
        Ok(Command::Render(o)) => *o,
        other => panic!("{s}: {other:?}"),
    }
}

fn err(s: &str) -> String {
    match parse_rpict_args(&w(s)) {
        Err(e) => e.to_string(),
        Ok(c) => panic!("{s}: expected an error, got {c:?}"),
    }
}

#[test]
fn defaults_match_rpict_verbatim() {
    let expected = "-vtv\t\t\t\t# view type perspective
-vp 0.000000 0.000000 0.000000\t# view point
-vd 0.000000 1.000000 0.000000\t# view direction
-vu 0.000000 0.000000 1.000000\t# view up
-vh 45.000000\t\t\t# view horizontal size
-vv 45.000000\t\t\t# view vertical size
-vo 0.000000\t\t\t# view fore clipping plane
-va 0.000000\t\t\t# view aft clipping plane
-vs 0.000000\t\t\t# view shift
-vl 0.000000\t\t\t# view lift
-x  512      \t\t\t# x resolution
-y  512      \t\t\t# y resolution
-pRGB\t\t\t\t# standard RGB color output
-pa 1.000000\t\t\t# pixel aspect ratio
-pj 0.670000\t\t\t# pixel jitter
-pm 0.000000\t\t\t# pixel motion
-pd 0.000000\t\t\t# pixel depth-of-field
-ps 4        \t\t\t# pixel sample
-pt 0.050000\t\t\t# pixel threshold
-t  0        \t\t\t# time between reports
-w+\t\t\t\t# warning messages on
-i-\t\t\t\t# irradiance calculation off
-u-\t\t\t\t# correlated quasi-Monte Carlo sampling
-bv+\t\t\t\t# back face visibility on
-dt 0.050000\t\t\t# direct threshold
-dc 0.500000\t\t\t# direct certainty
-dj 0.000000\t\t\t# direct jitter
-ds 0.250000\t\t\t# direct sampling
-dr 1        \t\t\t# direct relays
-dp 512      \t\t\t# direct pretest density
-dv+\t\t\t\t# direct visibility on
-ss 1.000000\t\t\t# specular sampling
-st 0.150000\t\t\t# specular threshold
-av 0.000000 0.000000 0.000000\t# ambient value
-aw 0        \t\t\t# ambient value weight
-ab 0        \t\t\t# ambient bounces
-aa 0.200000\t\t\t# ambient accuracy
-ar 64       \t\t\t# ambient resolution
-ad 512      \t\t\t# ambient divisions
-as 128      \t\t\t# ambient super-samples
-me 0.00e+00 0.00e+00 0.00e+00\t# mist extinction coefficient
-ma 0.000000 0.000000 0.000000\t# mist scattering albedo
-mg 0.000000\t\t\t# mist scattering eccentricity
-ms 0.000000\t\t\t# mist sampling distance
-lr 7        \t\t\t# limit reflection
-lw 1.00e-04\t\t\t# limit weight
-am 0.0\t\t\t\t# max photon search radius
";
    assert_eq!(defaults_text(&RpictOptions::default()), expected);
}

#[test]
fn defaults_reflect_options() {
    let Command::PrintDefaults(o) = parse_rpict_args(&w("-ab 2 -i -defaults -ab 5")).unwrap()
    else {
        panic!("expected PrintDefaults")
    };
    let t = defaults_text(&o);
    assert!(t.contains("-ab 2        \t\t\t# ambient bounces\n"), "{t}");
    assert!(
        t.contains("-i+\t\t\t\t# irradiance calculation on\n"),
        "{t}"
    );
    assert_eq!(
        parse_rpict_args(&w("-version")).unwrap(),
        Command::PrintVersion
    );
    assert!(matches!(
        parse_rpict_args(&w("-help")).unwrap(),
        Command::PrintDefaults(_)
    ));
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn defaults_match_real_rpict() {
    let Some(bin) = radiance_bin() else {
        eprintln!("skipping: Radiance not found");
        return;
    };
    let raypath = std::env::var("RAYPATH")
        .unwrap_or_else(|_| format!(".:{}", bin.parent().unwrap_or(&bin).join("lib").display()));
    let cases = [
        "",
        "-ab 2 -i -x 1000 -lw 0.0003 -me 0.01 2 3",
        "-w -u -bv -dv -dr 3 -dp 100 -t 30",
        "-vta -vp 1e3 -2.5 3 -vd 1 1 1 -vu 1 0 0 -vh 180 -vv 170 -vo 1 -va 9 -vs 0.5 -vl -0.25",
        "-vtl -ps 1 -pt 0.1 -pj 0 -pa 0 -pm 0.5 -pd 0.02 -y 77",
        "-vth -av 0.1 0.2 0.3 -aw 10 -aa 0.05 -ar 512 -ad 2048 -as 1024 -ss 0.5 -st 0.01",
        "-vts -ma 0.5 0.6 0.7 -mg 0.3 -ms 0.1 -lr -10 -dt 0.1 -dc 0.9 -dj 0.7 -ds 0.1",
        "-vtc -i+ -i -u0 -bv0 -dv- -w1",
        "-lr 0 -ab -1",
    ];
    for c in cases {
        let mut args = w(c);
        args.push("-defaults".into());
        let out = Proc::new(bin.join("rpict"))
            .args(&args)
            .env("RAYPATH", &raypath)
            .output()
            .unwrap();
        let theirs = String::from_utf8_lossy(&out.stdout);
        let Command::PrintDefaults(o) = parse_rpict_args(&args).unwrap() else {
            panic!("{c}")
        };
        assert_eq!(defaults_text(&o), theirs, "options: {c}");
    }
}

#[test]
fn parses_everything() {
    let o = render(
        "-vth -vp 1 2 3 -vh 170 -vv 160 -x 100 -y 80 -pa 0 -pj 0.5 -pm 0.1 -pd 0.02 -ps 2 \
         -pt 0.1 -t 10 -w- -n 3 -o out%03d.hdr -S 2 -e err.log --allow-commands --stats st.json \
         -ab 2 -aa 0.1 -ar 32 -ad 64 -as 16 -av 1 1 1 -aw 4 -ae glass -ae metal -af amb.dat \
         -i -u+ -bv0 -dv- -dt 0.1 -dc 0.3 -dj 0.5 -ds 0.2 -dr 0 -dp 64 -ss 0.5 -st 0.3 \
         -lr -8 -lw 0.001 -me 0.1 0.2 0.3 -ma 0.5 0.5 0.5 -mg 0.7 -ms 0.2 -pRGB a.rad b.rad",
    );
    assert_eq!(o.picture.view.vtype, ViewType::Hemispherical);
    assert_eq!(o.picture.view.vp, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!(
        (
            o.picture.x,
            o.picture.y,
            o.picture.pa,
            o.picture.pj,
            o.picture.pm,
            o.picture.pd,
            o.picture.ps,
            o.picture.pt
        ),
        (100, 80, 0.0, 0.5, 0.1, 0.02, 2, 0.1)
    );
    assert_eq!(o.run.report_interval, 10.0);
    assert!(!o.run.warnings);
    assert_eq!(o.run.threads, Some(3));
    assert_eq!(o.run.output.as_deref(), Some("out%03d.hdr"));
    assert_eq!(o.run.sequence_start, Some(2));
    assert_eq!(o.run.error_file.as_deref(), Some("err.log"));
    assert!(o.run.allow_commands);
    assert_eq!(o.run.stats_file.as_deref(), Some("st.json"));
    let p = &o.params;
    assert_eq!(
        (p.ab, p.aa, p.ar, p.ad, p.as_, p.aw),
        (2, 0.1, 32, 64, 16, 4)
    );
    assert_eq!(p.av, [1.0; 3]);
    assert_eq!(p.ae, vec!["glass", "metal"]);
    assert_eq!(o.run.amb_file.as_deref(), Some("amb.dat"));
    assert!(p.i && p.u && !p.bv && !p.dv);
    assert_eq!(
        (p.dt, p.dc, p.dj, p.ds, p.dr, p.dp),
        (0.1, 0.3, 0.5, 0.2, 0, 64.0)
    );
    assert_eq!((p.ss, p.st, p.lr, p.lw), (0.5, 0.3, -8, 0.001));
    assert_eq!(
        (p.me, p.ma, p.mg, p.ms),
        ([0.1, 0.2, 0.3], [0.5; 3], 0.7, 0.2)
    );
    assert_eq!(o.scene_files, vec!["a.rad", "b.rad"]);
    // No scene file means stdin.
    assert_eq!(render("-ab 1").scene_files, vec!["-"]);
    assert_eq!(render("-").scene_files, vec!["-"]);
}

#[test]
fn error_messages() {
    assert_eq!(
        err("-zz 3 x.rad"),
        "unknown option -zz (-defaults lists every option)"
    );
    // One edit from a known option: suggested.
    assert_eq!(
        err("-abb 1 x.rad"),
        "unknown option -abb (did you mean -ab? -defaults lists every option)"
    );
    assert_eq!(
        err("-vp 1 abc 3 x.rad"),
        "option -vp: expected 3 numbers, got 'abc'"
    );
    assert_eq!(err("-ab two"), "option -ab: expected an integer, got 'two'");
    assert_eq!(err("-aa inf"), "option -aa: expected a number, got 'inf'");
    assert!(err("-av 1 2").contains("-av"));
    assert!(err("-ps 40").contains("out of range 1..16"));
    assert!(err("-ps 0").contains("-ps"));
    assert!(err("-pj 3").contains("-pj"));
    assert!(err("-x 0").contains("-x"));
    assert!(err("-n 0").contains("-n"));
    for (opt, what) in [
        ("-z d.zbf", "-z"),
        ("-P pf", "-P"),
        ("-PP pf", "-PP"),
        ("-r old.hdr", "-r"),
        ("-ro old.hdr", "-ro"),
        ("-pXYZ", "-pXYZ"),
        ("-pc 1 2 3 4 5 6 7 8", "-pc"),
        ("-am 1", "-am"),
    ] {
        let e = err(opt);
        assert!(
            e.contains("not supported") && e.contains(what),
            "{opt}: {e}"
        );
    }
    assert!(err("-e a=b").contains("not supported"));
    assert!(err("-e f:x").contains("not supported"));
    let e = err("a.rad -ab 2");
    assert!(e.contains("-ab") && e.contains("a.rad"), "{e}");
    assert!(err("-S 1").contains("stdin"));
    assert!(err("-S 1 -").contains("stdin"));
    assert!(err("-vd 0 0 0 a.rad").contains("zero view direction"));
    assert!(err("-ai a -ae b").contains("cannot mix"));
    assert!(err("-vf /nonexistent/v.vf").contains("/nonexistent/v.vf"));
    assert!(err("-x").contains("-x"));
}

#[test]
fn view_files_apply_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let vf = dir.path().join("examp.vp");
    std::fs::write(
        &vf,
        "rview -vp 3 2 5 -vd -0.268328 -0.357771 -0.894427 -vu 0 1 0 -vh 45 -vv 45 -x 470 -y 470\n",
    )
    .unwrap();
    let vfs = vf.display().to_string();
    let o = render(&format!("-vp 9 9 9 -vh 30 -vtl -vf {vfs} -vv 20 s.rad"));
    assert_eq!(o.picture.view.vp, DVec3::new(3.0, 2.0, 5.0));
    assert_eq!(o.picture.view.vh, 45.0);
    assert_eq!(o.picture.view.vv, 20.0);
    assert_eq!(o.picture.view.vtype, ViewType::Parallel); // not set by the file
                                                          // The file's -x/-y are not view options.
    assert_eq!((o.picture.x, o.picture.y), (512, 512));
}

#[test]
fn at_files_and_env() {
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("inner.opt");
    std::fs::write(&inner, "-aa 0.05 # accuracy\n-o 'my pic.hdr'\n").unwrap();
    let outer = dir.path().join("render.opt");
    std::fs::write(
        &outer,
        format!(
            "# render options\n-ab 3 \"-i+\"\n@{}\n-vp 1 2 3\n",
            inner.display()
        ),
    )
    .unwrap();
    let args = vec![
        format!("@{}", outer.display()),
        "-ab".into(),
        "4".into(),
        "s.rad".into(),
    ];
    let ex = expand_args(&args).unwrap();
    assert_eq!(
        ex,
        vec![
            "-ab",
            "3",
            "-i+",
            "-aa",
            "0.05",
            "-o",
            "my pic.hdr",
            "-vp",
            "1",
            "2",
            "3",
            "-ab",
            "4",
            "s.rad"
        ]
    );
    let Command::Render(o) = parse_rpict_args(&args).unwrap() else {
        panic!()
    };
    assert_eq!((o.params.ab, o.params.aa, o.params.i), (4, 0.05, true));
    assert_eq!(o.run.output.as_deref(), Some("my pic.hdr"));
    // Missing file names the file.
    let e = expand_args(&w("@/no/such/file.opt")).unwrap_err();
    assert!(e.to_string().contains("/no/such/file.opt"), "{e}");
    // Recursion is limited.
    let rec = dir.path().join("rec.opt");
    std::fs::write(&rec, format!("-ab 1 @{}", rec.display())).unwrap();
    let e = expand_args(&[format!("@{}", rec.display())]).unwrap_err();
    assert!(e.to_string().contains("nesting"), "{e}");
    // $VAR expands to words.
    std::env::set_var("TESSERA_TEST_OPTS", "-ab 2 -aa 0.3");
    assert_eq!(
        expand_args(&w("-x 4 $TESSERA_TEST_OPTS")).unwrap(),
        w("-x 4 -ab 2 -aa 0.3")
    );
    let e = expand_args(&w("$TESSERA_TEST_SURELY_UNSET_VAR")).unwrap_err();
    assert!(
        e.to_string().contains("TESSERA_TEST_SURELY_UNSET_VAR"),
        "{e}"
    );
    // A lone '@' or '$' is just a word.
    assert_eq!(expand_args(&w("@ $")).unwrap(), w("@ $"));
    assert_eq!(split_words("a#b #c\nd"), w("a#b d"));
}

#[test]
fn ambient_lists_from_files() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("mods.txt");
    std::fs::write(&f, "glass\nwindow  # comment\n").unwrap();
    let mut p = RenderParams::default();
    p.apply_option(&["-aI".to_string(), f.display().to_string()])
        .unwrap();
    assert_eq!(p.ai, vec!["glass", "window"]);
    let e = p.apply_option(&w("-ae x")).unwrap_err();
    assert!(matches!(e, OptError::BadValue { .. }));
}

#[test]
fn to_args_round_trip_simple() {
    let o = render("-vta -vh 200 -ab 2 -ae a -ae b -af x.amb -i -n 2 -o o.hdr -S 5 s.rad");
    let mut a = to_args(&o);
    a.push("s.rad".into());
    assert_eq!(render(&a.join(" ")), o);
    let s = serde_json::to_string(&o).unwrap();
    let back: RpictOptions = serde_json::from_str(&s).unwrap();
    assert_eq!(back, o);
}

fn any_vtype() -> impl Strategy<Value = ViewType> {
    prop_oneof![
        Just(ViewType::Perspective),
        Just(ViewType::Parallel),
        Just(ViewType::Angular),
        Just(ViewType::Hemispherical),
        Just(ViewType::Planisphere),
        Just(ViewType::Cylindrical),
    ]
}

fn name() -> impl Strategy<Value = String> {
    "[a-zA-Z_][a-zA-Z0-9_.]{0,8}"
}

prop_compose! {
    fn any_options()(
        vtype in any_vtype(),
        vp in prop::array::uniform3(-1e6f64..1e6),
        vd in prop::array::uniform3(0.1f64..3.0),
        vh in 1.0f64..170.0, vv in 1.0f64..170.0,
        vo in 0.0f64..1.0, va in prop_oneof![Just(0.0), 2.0f64..100.0],
        vs in -2.0f64..2.0, vl in -2.0f64..2.0,
        x in 1usize..5000, y in 1usize..5000,
        pa in 0.0f64..3.0, pj in 0.0f64..1.0, pm in 0.0f64..2.0, pd in 0.0f64..1.0,
        ps in 1usize..=16, pt in 0.0f64..1.0, t in 0u32..1000, warnings in any::<bool>(),
        threads in proptest::option::of(1usize..64),
        output in proptest::option::of(name()),
        seq in proptest::option::of(0u32..100),
        error_file in proptest::option::of(name()),
        allow_commands in any::<bool>(),
        stats_file in proptest::option::of(name()),
        obj_material in proptest::option::of(name()),
        amb_log in proptest::option::of(name()),
        amb_flush in 1usize..1000,
        amb_force in any::<bool>(),
        max_primitives in proptest::option::of(1usize..100_000_000),
        amb_file in proptest::option::of(name()),
        overture in any::<bool>(),
        same_seeds in any::<bool>(),
        p in any_params(),
    ) -> RpictOptions {
        RpictOptions {
            picture: PictureParams {
                view: View { vtype, vp: DVec3::from_array(vp), vd: DVec3::from_array(vd),
                             vu: DVec3::Z, vh, vv, vo, va, vs, vl },
                x, y, pa, pj, pm, pd, ps, pt, overture, same_seeds,
            },
            params: p,
            run: RunParams {
                report_interval: t as f64, warnings, threads, output, sequence_start: seq,
                error_file, allow_commands, stats_file, obj_material, amb_file, amb_log, amb_flush,
                amb_force, max_primitives,
            },
            scene_files: vec!["scene.rad".into()],
        }
    }
}

prop_compose! {
    fn any_params()(
        dt in 0.0f64..1.0, dc in 0.0f64..1.0, dj in 0.0f64..1.0, ds in 0.0f64..1.0,
        dr in 0i32..5, dp in 0.0f64..2048.0, dv in any::<bool>(), ss in 0.0f64..4.0,
        st in 0.0f64..1.0, lr in -20i32..20, lw in 0.0f64..0.1,
        av in prop::array::uniform3(-1.0f64..10.0), aw in 0i32..100, ab in -2i32..8,
        aa in 0.0f64..1.0, ar in 0i32..4096, ad in 0i32..4096, as_ in 0i32..4096,
        names in proptest::collection::vec(name(), 0..4), include in any::<bool>(),
        i in any::<bool>(), u in any::<bool>(),
        bv in any::<bool>(), me in prop::array::uniform3(0.0f64..1.0),
        ma in prop::array::uniform3(0.0f64..1.0), mg in -1.0f64..1.0, ms in 0.0f64..1.0,
        amb in any_settings(),
        ax in prop::option::of((0.01f64..1.0, 0.01f64..1.0, 0.01f64..0.99, any::<bool>())),
        axm in prop::option::of((1.0f64..10.0, 1u32..20)),
        axt in prop::option::of((0.01f64..100.0, 0.01f64..1.0, 0.01f64..1.0)),
    ) -> RenderParams {
        let axt = axt.map(|(t, a, b)| {
            tessera::options::schedule::TimeBudget::new(t, a.max(b), a.min(b)).unwrap()
        });
        let axm = axm.map(|(r, a)| {
            tessera::options::schedule::MotionAccuracy::new(r, a as f64).unwrap()
        });
        let ax = ax.map(|(a, b, step, geometric)| {
            tessera::options::schedule::AccuracySchedule::new(a.max(b), a.min(b), step, geometric)
                .unwrap()
        });
        let (ae, ai) = if include { (vec![], names) } else { (names, vec![]) };
        RenderParams { dt, dc, dj, ds, dr, dp, dv, ss, st, lr, lw, av, aw, ab, aa, ar, ad, as_,
                       ae, ai, i, u, bv, me, ma, mg, ms, amb, ax, axm, axt }
    }
}

prop_compose! {
    fn any_settings()(
        share_max in 1.0f64..4.0, as0_split in 0.0f64..0.9, flags in prop::array::uniform8(any::<bool>()),
        hessian_cells in 16usize..5000, outlier_limit in 0.0f64..100.0, shadow_trust in 1u16..=31,
    ) -> AmbientSettings {
        let [hessian, reach, gradients, gradient_radii, glow_sampling, corral, shadow_reuse, ss_own] = flags;
        AmbientSettings { share_max, as0_split, hessian, reach, gradients, gradient_radii,
                          glow_sampling, corral, shadow_reuse, shadow_trust, hessian_cells,
                          outlier_limit, ss_own }
    }
}

fn word() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("-vp".to_string()),
        Just("-ab".to_string()),
        Just("-av".to_string()),
        Just("-i".to_string()),
        Just("-vf".to_string()),
        Just("-defaults".to_string()),
        Just("-S".to_string()),
        Just("-e".to_string()),
        Just("-".to_string()),
        Just("NaN".to_string()),
        Just("1e400".to_string()),
        Just("-1e400".to_string()),
        Just("99999999999999999999999".to_string()),
        Just("@".to_string()),
        Just("$".to_string()),
        Just("@/nonexistent".to_string()),
        Just("$PATH".to_string()),
        Just("ünïcödé".to_string()),
        "-[a-zA-Z]{1,4}[+\\-01]?",
        "-?[0-9]{0,5}(\\.[0-9]{0,3})?",
        "\\PC{0,10}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn to_args_parses_back(o in any_options()) {
        let mut a = to_args(&o);
        a.extend(o.scene_files.iter().cloned());
        match parse_rpict_args(&a) {
            Ok(Command::Render(back)) => prop_assert_eq!(*back, o),
            other => prop_assert!(false, "{:?} from {:?}", other, a),
        }
    }

    #[test]
    fn arbitrary_words_never_panic(ws in proptest::collection::vec(word(), 0..16)) {
        let _ = parse_rpict_args(&ws);
        let _ = expand_args(&ws);
        let mut v = View::default();
        let _ = v.apply_words(&ws);
        let mut p = RenderParams::default();
        for k in 0..ws.len() {
            let _ = p.apply_option(&ws[k..]);
        }
        let _ = split_words(&ws.join(" "));
        if let Ok(Command::Render(o)) | Ok(Command::PrintDefaults(o)) = parse_rpict_args(&ws) {
            let _ = defaults_text(&o);
            let _ = to_args(&o);
        }
    }
}

#[test]
fn boolean_suffixes() {
    // rpict 6.0a itself accepts only bare, + - 1 0; tpict also takes the man page's y/t/n/f.
    let o = render("-iy -uT -bvf -dvN -wn");
    assert!(o.params.i && o.params.u && !o.params.bv && !o.params.dv && !o.run.warnings);
    let o = render("-i -i -u1 -bv0 -dv -w");
    assert!(!o.params.i && o.params.u && !o.params.bv && !o.params.dv && !o.run.warnings);
    assert!(err("-ix").starts_with("unknown option -ix"));
}
