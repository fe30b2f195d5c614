//! The rpict options `rad` derives from a rif file's variables (`rad -n` prints them), in
//! rad's order: `[-t s [-e f]] VIEW -x X -y Y [-pa a] -dp -ar [-ms] -ds [-dj] fixed [-ab]
//! [-af] -aa -ad -as -av -lr -lw <render> -ps -pt <rpict>`.

use super::views::{expand, RadView, Zone};
use super::{RadFile, RifError};
use crate::view::fmt_g;

/// Low, medium or high (QUALITY, DETAIL, VARIABILITY).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// L
    Low = 0,
    /// M
    Medium = 1,
    /// H
    High = 2,
}

/// What rad would run for a rif file.
#[derive(Debug, Clone, PartialEq)]
pub struct RadPlan {
    /// The views, in the file's order (`X` when there is none).
    pub views: Vec<RadView>,
    /// Scene files: `materials` then `scene`.
    pub scene_files: Vec<String>,
    /// `-t`/`-e` from REPORT.
    report: Vec<String>,
    /// Rendering resolution (RESOLUTION times the supersampling factor).
    pub x: usize,
    /// Rendering resolution.
    pub y: usize,
    /// `-pa` when RESOLUTION gives a pixel aspect.
    pa: Option<String>,
    /// Options from `-dp` to `-lw` and the `render` variable (in OPTFILE when it is set).
    options: Vec<String>,
    /// `-ps`, `-pt` and the `rpict` variable.
    tail: Vec<String>,
    /// OPTFILE: the file the options go into, passed as `@file`.
    optfile: Option<String>,
    /// 1, 2 or 3: rad renders this much larger and reduces with pfilt.
    pub supersample: usize,
    /// The pfilt options rad reduces the picture with (before `-x /m -y /m`).
    pub pfilt: Vec<String>,
    /// The picture name root (PICTURE, default the rif's name without `.rif`).
    pub picture_root: String,
    /// What is ignored, each naming the variable.
    pub warnings: Vec<String>,
    zone: Zone,
    up: Option<(usize, i32)>,
}

fn level(rf: &RadFile, name: &str, default: Level) -> Result<Level, RifError> {
    match rf.get(name).and_then(|v| v.chars().next()) {
        None => Ok(default),
        Some(c) => match c.to_ascii_uppercase() {
            'L' => Ok(Level::Low),
            'M' => Ok(Level::Medium),
            'H' => Ok(Level::High),
            _ => Err(rf.error(name, format!("{name} must be LOW, MEDIUM or HIGH"))),
        },
    }
}

fn number(rf: &RadFile, name: &str, w: &str) -> Result<f64, RifError> {
    w.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| rf.error(name, format!("{name}: '{w}' is not a number")))
}

/// ZONE, or the exterior zone of the scene's bounding cube.
fn zone(rf: &RadFile, cube: &([f64; 3], f64)) -> Result<Zone, RifError> {
    let w = rf.words("ZONE");
    if w.is_empty() {
        let (c, s) = cube;
        return Ok(Zone {
            interior: false,
            min: c.map(|v| v - 0.5 * s),
            max: c.map(|v| v + 0.5 * s),
        });
    }
    let interior = match w[0].chars().next().map(|c| c.to_ascii_uppercase()) {
        Some('I') => true,
        Some('E') => false,
        _ => return Err(rf.error("ZONE", "ZONE must start with Interior or Exterior")),
    };
    if w.len() != 7 {
        return Err(rf.error(
            "ZONE",
            "ZONE needs I|E and six numbers: xmin xmax ymin ymax zmin zmax",
        ));
    }
    let v: Vec<f64> = w[1..]
        .iter()
        .map(|s| number(rf, "ZONE", s))
        .collect::<Result<_, _>>()?;
    let z = Zone {
        interior,
        min: [v[0], v[2], v[4]],
        max: [v[1], v[3], v[5]],
    };
    if (0..3).any(|i| z.max[i] < z.min[i]) || z.mean_size() <= 0.0 {
        return Err(rf.error("ZONE", "ZONE's maxima must not be below its minima"));
    }
    Ok(z)
}

fn up(rf: &RadFile) -> Result<Option<(usize, i32)>, RifError> {
    let Some(v) = rf.get("UP") else {
        return Ok(None);
    };
    let (sign, axis) = match v.strip_prefix('-') {
        Some(a) => (-1, a),
        None => (1, v.strip_prefix('+').unwrap_or(v)),
    };
    let axis = match axis.to_ascii_uppercase().as_str() {
        "X" => 0,
        "Y" => 1,
        "Z" => 2,
        _ => {
            return Err(rf.error(
                "UP",
                format!("UP '{v}': expected X, Y or Z, optionally signed"),
            ))
        }
    };
    Ok(Some((axis, sign)))
}

fn flag(rf: &RadFile, name: &str) -> Result<bool, RifError> {
    match rf.get(name).and_then(|v| v.chars().next()) {
        None => Ok(false),
        Some(c) => match c.to_ascii_uppercase() {
            'T' | 'Y' => Ok(true),
            'F' | 'N' => Ok(false),
            _ => Err(rf.error(name, format!("{name} must be TRUE or FALSE"))),
        },
    }
}

/// `-av`'s value from EXPOSURE (a multiplier or ±stops).
fn ambient_value(rf: &RadFile, interior: bool) -> Result<f64, RifError> {
    let Some(e) = rf.get("EXPOSURE") else {
        return Ok(if interior { 0.01 } else { 10.0 });
    };
    let e = e.split_whitespace().next().unwrap_or(e);
    let v = number(rf, "EXPOSURE", e)?;
    let mult = if e.starts_with('+') || e.starts_with('-') {
        2f64.powf(v)
    } else {
        v
    };
    if mult <= 0.0 {
        return Err(rf.error("EXPOSURE", "EXPOSURE must be positive (or ±stops)"));
    }
    Ok(0.18 / mult)
}

fn words(s: &str) -> impl Iterator<Item = String> + '_ {
    s.split_whitespace().map(str::to_string)
}

impl RadPlan {
    /// Derive rad's plan from the variables and the scene's bounding cube (centre, size:
    /// the largest extent of the scene's bounding box, as `rad -n` takes it before an
    /// octree exists).
    pub fn new(rf: &RadFile, cube: ([f64; 3], f64)) -> Result<RadPlan, RifError> {
        let mut warnings = Vec::new();
        if rf.get("illum").is_some() {
            warnings.push(format!(
                "{}: mkillum is not built in: the illum files are rendered as ordinary \
                 surfaces (their light reaches the scene through the ambient calculation, \
                 not as mkillum's secondary light sources)",
                rf.path.display()
            ));
        }
        for v in ["PGMAP", "PCMAP"] {
            if rf.get(v).is_some() {
                return Err(rf.error(
                    v,
                    format!("{v} is not supported (mkillum and photon maps are not built in)"),
                ));
            }
        }
        for v in [
            "ZFILE", "OPTFILE", "RAWFILE", "EYESEP", "oconv", "mkillum", "mkpmap", "rvu",
        ] {
            if rf.get(v).is_some() {
                warnings.push(format!("{}: {v} is ignored", rf.path.display()));
            }
        }
        let scene_files: Vec<String> = rf
            .words("materials")
            .into_iter()
            .chain(rf.words("scene"))
            .collect();
        let q = level(rf, "QUALITY", Level::Low)?;
        let det = level(rf, "DETAIL", Level::Medium)? as usize;
        let var = level(rf, "VARIABILITY", Level::Low)? as usize;
        let pen = flag(rf, "PENUMBRAS")?;
        let indirect = match rf.get("INDIRECT") {
            None => 0,
            Some(s) => s
                .parse::<u32>()
                .map_err(|_| rf.error("INDIRECT", format!("INDIRECT '{s}' is not a count")))?,
        };
        let z = zone(rf, &cube)?;
        let up = up(rf)?;
        let asz = z.mean_size();
        let d = cube.1 / asz;
        // Resolution.
        let res = rf.words("RESOLUTION");
        if res.len() > 3 {
            return Err(rf.error("RESOLUTION", "RESOLUTION takes x [y [pixel-aspect]]"));
        }
        let count = |s: &String| {
            s.parse::<usize>()
                .ok()
                .filter(|v| *v > 0)
                .ok_or_else(|| rf.error("RESOLUTION", format!("RESOLUTION '{s}' is not a size")))
        };
        let rx = res.first().map(count).transpose()?.unwrap_or(512);
        let ry = res.get(1).map(count).transpose()?.unwrap_or(rx);
        let pa = res
            .get(2)
            .map(|s| number(rf, "RESOLUTION", s).map(|a| format!("{a:.3}")))
            .transpose()?;
        let supersample = q as usize + 1;
        // Options from -dp to -pt.
        let mut o: Vec<String> = Vec::new();
        let dp = [[64, 128, 256], [256, 512, 1024], [1024, 2048, 4096]][q as usize][det];
        let ar = [[8.0, 16.0, 32.0], [16.0, 32.0, 64.0], [32.0, 64.0, 128.0]][q as usize][det];
        o.extend([
            "-dp".into(),
            dp.to_string(),
            "-ar".into(),
            ((ar * d) as i64).to_string(),
        ]);
        match q {
            Level::Low => {}
            Level::Medium => o.extend(["-ms".into(), fmt_g(asz / [20.0, 40.0, 80.0][det], 2)]),
            Level::High => o.extend(["-ms".into(), fmt_g(asz / [40.0, 80.0, 160.0][det], 2)]),
        }
        let ds = match (q, pen) {
            (Level::Low, true) => ".4",
            (Level::Low, false) => "0",
            (Level::Medium, true) => ".2 -dj .9",
            (Level::Medium, false) => ".3",
            (Level::High, true) => ".1 -dj .9",
            (Level::High, false) => ".2",
        };
        o.push("-ds".into());
        o.extend(words(ds));
        o.extend(words(
            [
                "-dt .1 -dc .5 -dr 0 -ss 0 -st .5",
                "-dt .07 -dc .7 -dr 1 -ss 1 -st .1",
                "-dt .04 -dc .9 -dr 3 -ss 16 -st .01",
            ][q as usize],
        ));
        let ab = match q {
            Level::Low => None,
            Level::Medium => (indirect > 0).then_some(indirect),
            Level::High => Some(indirect + 1),
        };
        if let Some(ab) = ab {
            o.extend(["-ab".into(), ab.to_string()]);
        }
        if let Some(af) = rf.get("AMBFILE") {
            o.extend(["-af".into(), af.to_string()]);
        }
        let aa = [
            [
                "-aa .3 -ad 256 -as 0",
                "-aa .25 -ad 512 -as 0",
                "-aa .2 -ad 1024 -as 0",
            ],
            [
                "-aa .2 -ad 329 -as 42",
                "-aa .15 -ad 800 -as 128",
                "-aa .1 -ad 1536 -as 392",
            ],
            [
                "-aa .125 -ad 512 -as 64",
                "-aa .1 -ad 1536 -as 768",
                "-aa .075 -ad 4096 -as 2048",
            ],
        ][q as usize][var];
        o.extend(words(aa));
        let av = fmt_g(ambient_value(rf, z.interior)?, 2);
        o.extend(["-av".into(), av.clone(), av.clone(), av]);
        o.extend(words(
            ["-lr 6 -lw .001", "-lr 8 -lw 1e-4", "-lr 12 -lw 5e-6"][q as usize],
        ));
        o.extend(rf.words("render"));
        let mut tail: Vec<String> = Vec::new();
        let ps = match (q, pen) {
            (Level::Low, _) => [16, 8, 4][det],
            (Level::Medium, true) => [4, 3, 2][det],
            (Level::Medium, false) => [8, 6, 4][det],
            (Level::High, true) => 1,
            (Level::High, false) => [8, 5, 3][det],
        };
        tail.extend(["-ps".into(), ps.to_string(), "-pt".into()]);
        tail.push([".16", ".08", ".04"][q as usize].into());
        let mut extra = rf.words("rpict");
        if extra.first().is_some_and(|w| !w.starts_with('-')) {
            warnings.push(format!(
                "{}: rpict replaced by '{}' is ignored",
                rf.path.display(),
                extra[0]
            ));
            extra.remove(0);
        }
        tail.extend(extra);
        // REPORT.
        let mut report = Vec::new();
        let rw = rf.words("REPORT");
        if let Some(m) = rw.first() {
            let min = number(rf, "REPORT", m)?;
            report.extend(["-t".into(), fmt_g(min * 60.0, 6)]);
            if let Some(f) = rw.get(1) {
                report.extend(["-e".into(), f.clone()]);
            }
        }
        // pfilt.
        let mut pfilt = Vec::new();
        if let Some(e) = rf.get("EXPOSURE") {
            pfilt.extend(["-1".into(), "-e".into(), e.to_string()]);
        }
        match q {
            Level::Low => {}
            Level::Medium => pfilt.extend(["-r".into(), ".6".into()]),
            Level::High => pfilt.extend(["-m".into(), ".25".into()]),
        }
        pfilt.extend(rf.words("pfilt"));
        // Views.
        let mut views = Vec::new();
        // A blank `view=` is no view: with no other, rad renders its default, X.
        let given: Vec<&str> = rf
            .views
            .iter()
            .map(|(v, _)| v.as_str())
            .filter(|v| !v.trim().is_empty())
            .collect();
        let given = if given.is_empty() { vec!["X"] } else { given };
        for (i, v) in given.iter().enumerate() {
            if v.trim() == "0" || v.trim().is_empty() {
                continue;
            }
            views.push(expand(v, i + 1, &z, up));
        }
        let picture_root = rf.get("PICTURE").map(str::to_string).unwrap_or_else(|| {
            let s = rf.path.to_string_lossy();
            s.strip_suffix(".rif").unwrap_or(&s).to_string()
        });
        Ok(RadPlan {
            views,
            scene_files,
            report,
            x: rx * supersample,
            y: ry * supersample,
            pa,
            options: o,
            tail,
            optfile: rf.get("OPTFILE").map(str::to_string),
            supersample,
            pfilt,
            picture_root,
            warnings,
            zone: z,
            up,
        })
    }

    /// The view named `name`: a view of the file, else a standard view id of the zone.
    pub fn view(&self, name: &str) -> Option<RadView> {
        match self.views.iter().find(|v| v.name == name) {
            Some(v) => Some(v.clone()),
            None => {
                let v = expand(name, 0, &self.zone, self.up);
                (v.name == name && v.words.first().is_some_and(|w| w.starts_with("-vt")))
                    .then_some(v)
            }
        }
    }

    /// The views to render: `name` (see [`RadPlan::view`]) or all of them.
    pub fn select(&self, name: Option<&str>) -> Result<Vec<RadView>, String> {
        match name {
            None if self.views.is_empty() => Err("the rif file has no views (view= 0)".into()),
            None => Ok(self.views.clone()),
            Some(n) => self.view(n).map(|v| vec![v]).ok_or_else(|| {
                let names: Vec<&str> = self.views.iter().map(|v| v.name.as_str()).collect();
                format!(
                    "no view '{n}' (the file's views: {}; or a standard view id such as X or xyZ)",
                    names.join(" ")
                )
            }),
        }
    }

    /// rpict's options for `view`, as `rad -n` prints them (without the octree).
    pub fn rpict_words(&self, view: &RadView) -> Vec<String> {
        self.words(view, self.optfile.is_some())
    }

    /// [`RadPlan::rpict_words`] with every option inline, also when OPTFILE is set.
    pub fn rpict_words_inline(&self, view: &RadView) -> Vec<String> {
        self.words(view, false)
    }

    fn words(&self, view: &RadView, use_optfile: bool) -> Vec<String> {
        let mut w = self.report.clone();
        w.extend(view.words.iter().cloned());
        w.extend([
            "-x".into(),
            self.x.to_string(),
            "-y".into(),
            self.y.to_string(),
        ]);
        if let Some(pa) = &self.pa {
            w.extend(["-pa".into(), pa.clone()]);
        }
        match &self.optfile {
            Some(f) if use_optfile => w.push(format!("@{f}")),
            _ => w.extend(self.options.iter().cloned()),
        }
        w.extend(self.tail.iter().cloned());
        w
    }

    /// OPTFILE's name and contents (one option with its values per line, as rad writes
    /// it), when the file names one.
    pub fn optfile(&self) -> Option<(String, String)> {
        let f = self.optfile.as_ref()?;
        let mut text = String::new();
        for (i, w) in self.options.iter().enumerate() {
            let starts = w.len() > 1 && w.starts_with('-') && w.as_bytes()[1].is_ascii_alphabetic();
            if i > 0 {
                text.push(if starts { '\n' } else { ' ' });
            }
            text.push_str(w);
        }
        text.push('\n');
        Some((f.clone(), text))
    }

    /// The pfilt command rad would reduce `view`'s picture with.
    pub fn pfilt_command(&self, view: &RadView, raw: &str) -> String {
        let mut w = vec!["pfilt".to_string()];
        w.extend(self.pfilt.iter().cloned());
        if self.supersample > 1 {
            let m = self.supersample;
            w.extend([format!("-x /{m}"), format!("-y /{m}")]);
        }
        w.push(raw.to_string());
        format!("{} > {}_{}.hdr", w.join(" "), self.picture_root, view.name)
    }
}
