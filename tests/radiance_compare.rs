//! tpict against real Radiance (rpict from pyradiance) at `-ab 0`, under Radiance's own test
//! tolerance: pictures reduced to 128×128, relative RMS ≤ 10%, max ≤ 150%, mean luminance
//! within 2%. Skips (with a message) when Radiance is not installed.

mod common;

use common::*;
use std::path::Path;
use tessera::image::read_picture;

const RES: &str = "256";

struct Case<'a> {
    dir: &'a str,
    files: &'a [&'a str],
    view: &'a str,
    opts: &'a [&'a str],
    /// Extra options for tpict only (after `opts`).
    ours_extra: &'a [&'a str],
    /// Picture size (before reduction to 128×128).
    res: &'a str,
}

fn check(case: &Case) {
    check_tol(case, &SUITE)
}

fn check_tol(case: &Case, tol: &Tol) {
    let Some(bin) = radiance_bin() else { return };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/scenes")
        .join(case.dir);
    let tmp = tempfile::tempdir().unwrap();
    let oct = tmp.path().join("scene.oct");
    let octdata = run_ok(radiance(&bin, "oconv").current_dir(&dir).args(case.files));
    std::fs::write(&oct, octdata).unwrap();
    let mut common_args: Vec<&str> = vec!["-vf", case.view, "-x", case.res, "-y", case.res];
    common_args.extend_from_slice(case.opts);
    let reff = tmp.path().join("ref.hdr");
    let data = run_ok(
        radiance(&bin, "rpict")
            .current_dir(&dir)
            .args(&common_args)
            .arg(&oct),
    );
    std::fs::write(&reff, data).unwrap();
    let ours = tmp.path().join("ours.hdr");
    run_ok(
        std::process::Command::new(tpict_bin())
            .current_dir(&dir)
            .args(&common_args)
            .args(case.ours_extra)
            .arg("-o")
            .arg(&ours)
            .args(case.files),
    );
    assert_like_reference(&bin, &ours, &reff, tol, case.dir);
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn spheres_plastic_metal_sphere_and_polygon_lights() {
    check(&Case {
        dir: "",
        files: &["spheres.rad"],
        view: "spheres.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn curved_cones_cups_tubes_rings_and_concave_polygon() {
    check(&Case {
        dir: "",
        files: &["curved.rad"],
        view: "curved.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn glassy_glass_trans_dielectric_interface_sun_and_sky() {
    check(&Case {
        dir: "",
        files: &["glassy.rad"],
        view: "glassy.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn mirrors_virtual_sources_illum_spotlight_glow() {
    check(&Case {
        dir: "",
        files: &["mirrors.rad"],
        view: "mirrors.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn aniso_plastic2_metal2_antimatter_genbox_xform() {
    check(&Case {
        dir: "",
        files: &["aniso.rad"],
        view: "aniso.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn examp_shared_scene_with_builtin_genbox() {
    check(&Case {
        dir: "examp",
        files: &["examp"],
        view: "examp.vp",
        opts: &["-ab", "0", "-av", ".5", ".5", ".5", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn daffodil_shared_scene_flat() {
    check(&Case {
        dir: "daffodil",
        files: &["daffodil.flat.rad", "room.flat.rad"],
        view: "daffodil.vp",
        opts: &["-ab", "0", "-av", ".2", ".2", ".2", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

/// tpict's adaptive image sampling (`-ps 4 -pt .05`, the defaults) against rpict tracing
/// every pixel. (rpict's own `-ps 4` loses about 4% of this picture's mean luminance on the
/// thin tube light; tpict's cell subdivision stays within 0.1% of its `-ps 1` picture.)
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn adaptive_sampling_default_ps_matches_every_pixel_rpict() {
    check(&Case {
        dir: "",
        files: &["curved.rad"],
        view: "curved.vf",
        opts: &["-ab", "0", "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &["-ps", "4", "-pt", ".05"],
        res: RES,
    });
}
/// Function and data patterns, textures, an alias of a pattern and mixtures
/// (tests/scenes/patterns: patterns.rad has colorfunc with a function file and a
/// transform, texfunc, brightfunc, brightdata, mixfunc with noise3; datapat.rad has
/// colordata over a 2-D file, colorpict with a transform, texdata, mixdata and mixpict),
/// at `-ab 0` and `-ab 1` (means measured within 0.01% and 0.07%).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn patterns_textures_and_mixtures_with_functions_and_data() {
    for (ab, scene) in [
        ("0", "patterns.rad"),
        ("1", "patterns.rad"),
        ("0", "datapat.rad"),
        ("1", "datapat.rad"),
    ] {
        check(&Case {
            dir: "patterns",
            files: &[scene],
            view: "patterns.vf",
            opts: &[
                "-ab", ab, "-av", ".05", ".05", ".05", "-ps", "1", "-pj", "0",
            ],
            ours_extra: &[],
            res: RES,
        });
    }
}

/// A daylit room: a real `gensky` sky (its output saved in tests/scenes/daylight/sky.rad,
/// `skybright.cal` patterns on the sky and ground glows), the sun through a glass pane, at
/// `-ab 0`, `-ab 1` and `-ab 2` (mean luminance measured within 0.1% of rpict). With
/// indirect light the two caches' noise differs pixel by pixel in the sunlit room, so
/// those pictures are compared after reducing to 32×32, the mean within 2%.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn daylit_room_with_a_gensky_sky() {
    for ab in ["0", "1", "2"] {
        let tol = if ab == "0" {
            SUITE
        } else {
            Tol {
                size: "32",
                ..SUITE
            }
        };
        check_tol(
            &Case {
                dir: "daylight",
                files: &["sky.rad", "room.rad"],
                view: "room.vf",
                opts: &["-ab", ab, "-ps", "1", "-pj", "0"],
                ours_extra: &[],
                res: RES,
            },
            &tol,
        );
    }
}

/// The daylit room under skies made by the built-in generators (tests/scenes/generators:
/// inline `!gensky … | xform -rz 20` and `!gendaylit … -W`, read by tpict without a
/// shell; rpict's oconv runs the real programs), at `-ab 0` and `-ab 1` (reduced to 32×32
/// at `-ab 1`, as the gensky room above). tpict's RAYPATH is the test's: without
/// Radiance's library it uses its own skybright.cal and perezlum.cal.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn daylit_room_with_builtin_gensky_and_gendaylit() {
    for sky in ["gensky.rad", "gendaylit.rad"] {
        for ab in ["0", "1"] {
            let tol = if ab == "0" {
                SUITE
            } else {
                Tol {
                    size: "32",
                    ..SUITE
                }
            };
            check_tol(
                &Case {
                    dir: "generators",
                    files: &[sky, "../daylight/room.rad"],
                    view: "../daylight/room.vf",
                    opts: &["-ab", ab, "-ps", "1", "-pj", "0"],
                    ours_extra: &[],
                    res: RES,
                },
                &tol,
            );
        }
    }
}

/// A room lit by an IES luminaire converted by real `ies2rad -dm` (tests/scenes/ies:
/// `brightdata` over a 2-D candela table with `source.cal`'s `flatcorr`, `src_phi4`,
/// `src_theta`), placed by `xform -rz 30`, at `-ab 0` and `-ab 1` (means measured equal to
/// 0.02%).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ies_luminaire_from_ies2rad() {
    for ab in ["0", "1"] {
        check(&Case {
            dir: "ies",
            files: &["room.rad"],
            view: "room.vf",
            opts: &[
                "-ab", ab, "-av", ".01", ".01", ".01", "-ps", "1", "-pj", "0",
            ],
            ours_extra: &[],
            res: RES,
        });
    }
}

/// `-i`: irradiance through transparent materials. rpict's irradiance rays pass straight
/// through glass, trans, dielectric and interface surfaces (before, tpict shaded them as
/// white diffuse surfaces: a glass pane 0.462 against rpict's 0.265).
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn glassy_irradiance_passes_through_transparent_materials() {
    for ab in ["0", "1"] {
        check(&Case {
            dir: "",
            files: &["glassy.rad"],
            view: "glassy.vf",
            opts: &["-i", "-ab", ab, "-av", ".05", ".05", ".05", "-ps", "1"],
            ours_extra: &[],
            res: RES,
        });
    }
}

/// Indirect light (the irradiance cache) against rpict's, at `-ab 1` and `-ab 2` with
/// rpict's default ambient settings (`-aa .2 -ad 512 -as 128 -ar 64`).
fn ambient_case(dir: &str, files: &[&str], view: &str, ab: &str) {
    check(&Case {
        dir,
        files,
        view,
        opts: &["-ab", ab, "-av", ".05", ".05", ".05", "-ps", "1"],
        ours_extra: &[],
        res: RES,
    });
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ambient_interior_with_area_lights() {
    ambient_case("", &["spheres.rad"], "spheres.vf", "1");
    ambient_case("", &["spheres.rad"], "spheres.vf", "2");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ambient_window_with_sun_and_glow_sky() {
    ambient_case("", &["glassy.rad"], "glassy.vf", "1");
    ambient_case("", &["glassy.rad"], "glassy.vf", "2");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ambient_specular_mirror_and_spot() {
    ambient_case("", &["mirrors.rad"], "mirrors.vf", "1");
    ambient_case("", &["mirrors.rad"], "mirrors.vf", "2");
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn ambient_curved_surfaces() {
    ambient_case("", &["curved.rad"], "curved.vf", "1");
    ambient_case("", &["curved.rad"], "curved.vf", "2");
}

/// Tessera's own `skybright.cal` and `source.cal` (used when the RAYPATH has no Radiance
/// library) give the same pictures as Radiance's: the daylit room under gensky's clear,
/// intermediate and overcast skies, and the IES room, rendered by tpict both ways.
#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn builtin_library_files_match_radiances() {
    let Some(bin) = radiance_bin() else { return };
    let lib = bin.parent().unwrap().join("lib");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes");
    let tmp = tempfile::tempdir().unwrap();
    let day = scenes.join("daylight");
    let glows = std::fs::read_to_string(day.join("sky.rad")).unwrap();
    let glows = &glows[glows.find("# (added)").unwrap()..];
    let mut cases = Vec::new();
    for (i, sky) in ["+s", "+i", "-c"].iter().enumerate() {
        let out = run_ok(radiance(&bin, "gensky").args(["3", "21", "11", "-a", "40", sky]));
        let f = tmp.path().join(format!("sky{i}.rad"));
        std::fs::write(&f, [out.as_slice(), glows.as_bytes()].concat()).unwrap();
        cases.push((
            day.clone(),
            vec![f.display().to_string(), "room.rad".into()],
        ));
    }
    cases.push((scenes.join("ies"), vec!["room.rad".to_string()]));
    for (dir, files) in cases {
        let render = |raypath: String, out: &str| {
            let out = tmp.path().join(out);
            run_ok(
                std::process::Command::new(tpict_bin())
                    .current_dir(&dir)
                    .env("RAYPATH", raypath)
                    .args(["-vf", "room.vf", "-x", "64", "-y", "50", "-ab", "0"])
                    .args(["-ps", "1", "-pj", "0", "-o"])
                    .arg(&out)
                    .args(&files),
            );
            read_picture(&out).unwrap()
        };
        let theirs = render(format!(".:{}", lib.display()), "theirs.hdr");
        let ours = render(".".into(), "ours.hdr");
        let c = compare(&ours.pixels_f64(), &theirs.pixels_f64(), 0.01);
        eprintln!("{files:?}: {c:?}");
        assert!(c.max < 1e-3, "{files:?}: {c:?}");
        std::fs::remove_file(tmp.path().join("theirs.hdr")).unwrap();
        std::fs::remove_file(tmp.path().join("ours.hdr")).unwrap();
    }
}
