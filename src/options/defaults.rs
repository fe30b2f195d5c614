//! The text of `-defaults` (and `-help`), in rpict's layout and number formats.

use super::rpict::RpictOptions;
use crate::view::fmt_g6;

/// Format like C's `%.{prec}e` (two-digit exponent at least).
pub(crate) fn fmt_e(v: f64, prec: usize) -> String {
    let s = format!("{:.*e}", prec, v);
    match s.split_once('e') {
        Some((m, e)) => {
            let e: i32 = e.parse().unwrap_or(0);
            let sign = if e < 0 { '-' } else { '+' };
            format!("{m}e{sign}{:02}", e.abs())
        }
        None => s,
    }
}

/// The text of `-defaults`, in rpict's layout, reflecting the given options (so
/// `tpict -ab 2 -defaults` shows `-ab 2`).
pub fn defaults_text(opts: &RpictOptions) -> String {
    let v = &opts.picture.view;
    let p = &opts.params;
    let mut s = String::new();
    let mut line = |text: String, tabs: usize, comment: &str| {
        s.push_str(&text);
        for _ in 0..tabs {
            s.push('\t');
        }
        s.push_str("# ");
        s.push_str(comment);
        s.push('\n');
    };
    let f = |x: f64| format!("{x:.6}");
    let v3 = |a: [f64; 3]| format!("{:.6} {:.6} {:.6}", a[0], a[1], a[2]);
    let int = |name: &str, x: i64| format!("{name} {x:<9}");
    let onoff = |b: bool| if b { "on" } else { "off" };
    let pm = |b: bool| if b { '+' } else { '-' };
    line(
        format!("-vt{}", v.vtype.letter()),
        4,
        &format!("view type {}", v.vtype.name()),
    );
    line(format!("-vp {}", v3(v.vp.to_array())), 1, "view point");
    line(format!("-vd {}", v3(v.vd.to_array())), 1, "view direction");
    line(format!("-vu {}", v3(v.vu.to_array())), 1, "view up");
    line(format!("-vh {}", f(v.vh)), 3, "view horizontal size");
    line(format!("-vv {}", f(v.vv)), 3, "view vertical size");
    line(format!("-vo {}", f(v.vo)), 3, "view fore clipping plane");
    line(format!("-va {}", f(v.va)), 3, "view aft clipping plane");
    line(format!("-vs {}", f(v.vs)), 3, "view shift");
    line(format!("-vl {}", f(v.vl)), 3, "view lift");
    line(format!("-x  {:<9}", opts.picture.x), 3, "x resolution");
    line(format!("-y  {:<9}", opts.picture.y), 3, "y resolution");
    line("-pRGB".into(), 4, "standard RGB color output");
    line(
        format!("-pa {}", f(opts.picture.pa)),
        3,
        "pixel aspect ratio",
    );
    line(format!("-pj {}", f(opts.picture.pj)), 3, "pixel jitter");
    line(format!("-pm {}", f(opts.picture.pm)), 3, "pixel motion");
    line(
        format!("-pd {}", f(opts.picture.pd)),
        3,
        "pixel depth-of-field",
    );
    line(format!("-ps {:<9}", opts.picture.ps), 3, "pixel sample");
    line(format!("-pt {}", f(opts.picture.pt)), 3, "pixel threshold");
    let t = if opts.run.report_interval.fract() == 0.0 {
        format!("{}", opts.run.report_interval as i64)
    } else {
        fmt_g6(opts.run.report_interval)
    };
    line(format!("-t  {t:<9}"), 3, "time between reports");
    line(
        format!("-w{}", pm(opts.run.warnings)),
        4,
        &format!("warning messages {}", onoff(opts.run.warnings)),
    );
    line(
        format!("-i{}", pm(p.i)),
        4,
        &format!("irradiance calculation {}", onoff(p.i)),
    );
    line(
        format!("-u{}", pm(p.u)),
        4,
        if p.u {
            "uncorrelated Monte Carlo sampling"
        } else {
            "correlated quasi-Monte Carlo sampling"
        },
    );
    line(
        format!("-bv{}", pm(p.bv)),
        4,
        &format!("back face visibility {}", onoff(p.bv)),
    );
    line(format!("-dt {}", f(p.dt)), 3, "direct threshold");
    line(format!("-dc {}", f(p.dc)), 3, "direct certainty");
    line(format!("-dj {}", f(p.dj)), 3, "direct jitter");
    line(format!("-ds {}", f(p.ds)), 3, "direct sampling");
    line(int("-dr", p.dr as i64), 3, "direct relays");
    line(int("-dp", p.dp as i64), 3, "direct pretest density");
    line(
        format!("-dv{}", pm(p.dv)),
        4,
        &format!("direct visibility {}", onoff(p.dv)),
    );
    line(format!("-ss {}", f(p.ss)), 3, "specular sampling");
    line(format!("-st {}", f(p.st)), 3, "specular threshold");
    line(format!("-av {}", v3(p.av)), 1, "ambient value");
    line(int("-aw", p.aw as i64), 3, "ambient value weight");
    line(int("-ab", p.ab as i64), 3, "ambient bounces");
    line(format!("-aa {}", f(p.aa)), 3, "ambient accuracy");
    line(int("-ar", p.ar as i64), 3, "ambient resolution");
    line(int("-ad", p.ad as i64), 3, "ambient divisions");
    line(int("-as", p.as_ as i64), 3, "ambient super-samples");
    line(
        format!(
            "-me {} {} {}",
            fmt_e(p.me[0], 2),
            fmt_e(p.me[1], 2),
            fmt_e(p.me[2], 2)
        ),
        1,
        "mist extinction coefficient",
    );
    line(format!("-ma {}", v3(p.ma)), 1, "mist scattering albedo");
    line(
        format!("-mg {}", f(p.mg)),
        3,
        "mist scattering eccentricity",
    );
    line(format!("-ms {}", f(p.ms)), 3, "mist sampling distance");
    line(
        int("-lr", p.lr as i64),
        3,
        if p.lr <= 0 {
            "limit reflection (Russian roulette)"
        } else {
            "limit reflection"
        },
    );
    line(format!("-lw {}", fmt_e(p.lw, 2)), 3, "limit weight");
    line("-am 0.0".into(), 4, "max photon search radius");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn c_exponent_format() {
        assert_eq!(fmt_e(0.0, 2), "0.00e+00");
        assert_eq!(fmt_e(1e-4, 2), "1.00e-04");
        assert_eq!(fmt_e(123.0, 2), "1.23e+02");
    }
}
