//! Mixtures whose sides reach no material act as patterns, as in Radiance's `raymixture`:
//! in a material's own modifier chain (a picture pinned on a wall: a `colorpict` and `void`
//! mixed by a `mixfunc`, the mixture the modifier of a material copied by `alias`), and on
//! a surface with a material as the mixture's modifier. Against real rpict (pictures within
//! the suite's tolerance, means within 1% at `-ab 0` and 2% at `-ab 1`); a mixture of
//! materials in a material's chain is still refused. Skips (with a message) when Radiance
//! is not installed.

mod common;

use common::*;
use std::path::Path;
use tessera::image::read_picture;

const SCENE: &str = "void light lampmat 0 0 3 20 20 20
lampmat sphere lamp 0 0 4 2 -2 2.5 .2
void plastic paint 0 0 5 .7 .7 .7 0 0
void colorpict pic 7 red green blue pin.hdr pin.cal pic_u pic_v 0 0
void mixfunc pinned 4 pic void inside pin.cal 0 0
pinned alias pinned_paint paint
paint polygon floor 0 0 12 0 -4 0 4 -4 0 4 0 0 0 0 0
pinned_paint polygon wall 0 0 12 0 0 0 4 0 0 4 0 3 0 0 3
paint mixfunc pinned2 4 pic void inside2 pin.cal 0 0
pinned2 polygon side 0 0 12 0 0 0 0 0 3 0 -4 3 0 -4 0
";

const CAL: &str = "pic_u = Px - 1; pic_v = Pz - .5;
inside = if(pic_u, if(1 - pic_u, if(pic_v, if(1 - pic_v, 1, 0), 0), 0), 0);
pic2_u = -Py - 1.5;
inside2 = if(pic2_u, if(1 - pic2_u, if(Pz - 1, if(2 - Pz, .7, 0), 0), 0), 0);
";

fn mean(p: &Path) -> f64 {
    let img = read_picture(p).unwrap();
    img.pixels.iter().map(|c| c[1] as f64).sum::<f64>() / img.pixels.len() as f64
}

#[test]
#[cfg_attr(not(radiance), ignore = "needs real Radiance: see tests/README.md")]
fn pattern_mixtures_in_material_chains_match_rpict() {
    let Some(bin) = radiance_bin() else { return };
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(d.join("pinned.rad"), SCENE).unwrap();
    std::fs::write(d.join("pin.cal"), CAL).unwrap();
    let pic = run_ok(radiance(&bin, "pcomb").args([
        "-x",
        "16",
        "-y",
        "16",
        "-e",
        "ro=x/16;go=y/16;bo=.5",
    ]));
    std::fs::write(d.join("pin.hdr"), pic).unwrap();
    let oct = run_ok(radiance(&bin, "oconv").current_dir(d).arg("pinned.rad"));
    std::fs::write(d.join("pinned.oct"), oct).unwrap();
    for (ab, tol, bound) in [("0", &SUITE, 0.01), ("1", &AMBIENT, 0.02)] {
        let opts = [
            "-vp", "2.5", "-3.8", "1.5", "-vd", "-.3", "1", "0", "-vu", "0", "0", "1", "-vh", "70",
            "-vv", "60", "-x", "128", "-y", "110", "-ab", ab, "-ps", "1", "-pj", "0", "-av", ".1",
            ".1", ".1",
        ];
        check_against_rpict(&bin, d, &["pinned.rad"], "pinned.oct", &opts, tol);
        let name = format!("pinned.rad{}", opts.join(""));
        let (ours, reference) = (
            mean(&d.join(format!("ours-{name}.hdr"))),
            mean(&d.join(format!("ref-{name}.hdr"))),
        );
        assert!(
            (ours / reference - 1.0).abs() < bound,
            "-ab {ab}: mean {ours} against rpict's {reference}"
        );
    }
}

#[test]
fn a_mixture_of_materials_in_a_materials_chain_is_refused() {
    let t = tempfile::tempdir().unwrap();
    let d = t.path();
    std::fs::write(
        d.join("bad.rad"),
        "void plastic a 0 0 5 .5 .5 .5 0 0\n\
         void plastic b 0 0 5 .1 .1 .1 0 0\n\
         void mixfunc m 4 a b .5 . 0 0\n\
         m plastic c 0 0 5 .5 .5 .5 0 0\n\
         c sphere s 0 0 4 0 0 0 1\n",
    )
    .unwrap();
    let out = tpict_in(d)
        .args(["-x", "8", "-y", "8", "bad.rad"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.rad:4") && err.contains("conflicting material"),
        "{err}"
    );
}
