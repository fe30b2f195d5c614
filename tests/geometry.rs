//! Integration tests for surfaces and the BVH: closed forms, robustness (far-off scenes,
//! cracks, grazing rays), polygon holes, degenerate input, BVH versus brute force, and an
//! optional comparison with Radiance's `rtrace`.

use glam::DVec3;
use tessera::geometry::bvh::{select_closest, Bvh};
use tessera::geometry::cone::ConeKind;
use tessera::geometry::polygon::PolygonBuf;
use tessera::geometry::source::DistantSource;
use tessera::geometry::Surface;
use tessera::scene::{Location, Primitive};
use tessera::FTINY;

fn prim(ptype: &str, args: &[f64]) -> Primitive {
    Primitive {
        modifier: "m".into(),
        ptype: ptype.into(),
        name: "x".into(),
        sargs: vec![],
        iargs: vec![],
        rargs: args.to_vec(),
        loc: Location::new("test", 1),
    }
}

fn surf(ptype: &str, args: &[f64]) -> Surface {
    Surface::from_primitive(&prim(ptype, args), DVec3::ZERO).unwrap()
}

/// Small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (v >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn dir(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol
}

// ---------------------------------------------------------------- closed forms

#[test]
fn sphere_outside_inside_and_bubble() {
    let s = surf("sphere", &[1.0, 2.0, 3.0, 2.0]);
    let org = DVec3::new(1.0, 2.0, 10.0);
    let t = s.intersect(org, -DVec3::Z, 1e10).unwrap();
    assert!((t - 5.0).abs() < 1e-12);
    let g = s.hit_geom(org, -DVec3::Z, t);
    assert!(close(g.point, DVec3::new(1.0, 2.0, 5.0), 1e-12));
    assert!(close(g.normal, DVec3::Z, 1e-12));
    // From inside, the far wall; from the centre in many directions, t = r.
    let c = DVec3::new(1.0, 2.0, 3.0);
    let mut rng = Rng(7);
    for _ in 0..200 {
        let d = rng.dir();
        let t = s.intersect(c, d, 1e10).unwrap();
        assert!((t - 2.0).abs() < 1e-12);
        let g = s.hit_geom(c, d, t);
        assert!(close(g.normal, d, 1e-12));
    }
    // tmax excludes
    assert!(s.intersect(org, -DVec3::Z, 5.0).is_none());
    // Miss and grazing
    assert!(s
        .intersect(DVec3::new(3.5, 2.0, 10.0), -DVec3::Z, 1e10)
        .is_none());
    let g = s.intersect(DVec3::new(3.0, 2.0, 10.0), -DVec3::Z, 1e10);
    assert!(g.is_some_and(|t| (t - 7.0).abs() < 1e-6));
    // Bubble: inward normal; negative sphere radius becomes a bubble with a warning.
    let b = surf("bubble", &[1.0, 2.0, 3.0, 2.0]);
    let t = b.intersect(org, -DVec3::Z, 1e10).unwrap();
    assert!(close(
        b.hit_geom(org, -DVec3::Z, t).normal,
        -DVec3::Z,
        1e-12
    ));
    let (nb, w) =
        Surface::from_primitive_warn(&prim("sphere", &[0.0, 0.0, 0.0, -1.0]), DVec3::ZERO).unwrap();
    assert!(w.unwrap().contains("negative radius"));
    let Surface::Sphere(nb) = nb else {
        panic!("not a sphere")
    };
    assert!(nb.inward && nb.radius == 1.0);
    let Surface::Sphere(ns) = surf("bubble", &[0.0, 0.0, 0.0, -1.0]) else {
        panic!("not a sphere")
    };
    assert!(!ns.inward);
    assert!((s.area() - 16.0 * std::f64::consts::PI).abs() < 1e-12);
    let (lo, hi) = s.bounds();
    assert!(
        close(lo, DVec3::new(-1.0, 0.0, 1.0), 0.0) && close(hi, DVec3::new(3.0, 4.0, 5.0), 0.0)
    );
    assert!(!s.is_flat());
}

/// Independent reference for quadric surfaces: march along the ray and bisect the first
/// sign change of the implicit function inside the valid region.
fn march(f: impl Fn(DVec3) -> Option<f64>, org: DVec3, dir: DVec3, tmax: f64) -> Option<f64> {
    let n = 20000;
    let dt = tmax / n as f64;
    let mut prev: Option<(f64, f64)> = None;
    for i in 0..=n {
        let t = 1e-4 + i as f64 * dt;
        let v = f(org + dir * t);
        if let (Some((tp, vp)), Some(v)) = (prev, v) {
            if (vp <= 0.0) != (v <= 0.0) {
                let (mut a, mut b) = (tp, t);
                for _ in 0..80 {
                    let m = 0.5 * (a + b);
                    match f(org + dir * m) {
                        Some(vm) if (vm <= 0.0) == (vp <= 0.0) => a = m,
                        _ => b = m,
                    }
                }
                return Some(0.5 * (a + b));
            }
        }
        prev = v.map(|v| (t, v));
    }
    None
}

#[test]
fn cone_family_versus_analytic() {
    // Closed forms first.
    let cyl = surf("cylinder", &[0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 1.0]);
    let org = DVec3::new(5.0, 0.0, 0.5);
    let t = cyl.intersect(org, -DVec3::X, 1e10).unwrap();
    assert!((t - 4.0).abs() < 1e-12);
    let g = cyl.hit_geom(org, -DVec3::X, t);
    assert!(close(g.normal, DVec3::X, 1e-12));
    assert!((g.uv.1 - 0.25).abs() < 1e-12);
    let tube = surf("tube", &[0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 1.0]);
    let g = tube.hit_geom(
        org,
        -DVec3::X,
        tube.intersect(org, -DVec3::X, 1e10).unwrap(),
    );
    assert!(close(g.normal, -DVec3::X, 1e-12));
    // From inside: the far side at t = 1.
    let inside = DVec3::new(0.0, 0.0, 1.0);
    assert!((cyl.intersect(inside, DVec3::Y, 1e10).unwrap() - 1.0).abs() < 1e-12);
    // Open ends: along the axis never hits; past the end misses.
    assert!(cyl
        .intersect(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, 1e10)
        .is_none());
    assert!(cyl
        .intersect(DVec3::new(5.0, 0.0, 2.5), -DVec3::X, 1e10)
        .is_none());
    // Cone r0 = 1 at z = 0 to r1 = 0 at z = 1: hit at x = 0.5 with normal (1,0,1)/√2.
    let cone = surf("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    let t = cone.intersect(org, -DVec3::X, 1e10).unwrap();
    assert!((t - 4.5).abs() < 1e-12);
    let n = cone.hit_geom(org, -DVec3::X, t).normal;
    assert!(close(n, DVec3::new(1.0, 0.0, 1.0).normalize(), 1e-12));
    let cup = surf("cup", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    let n = cup.hit_geom(org, -DVec3::X, t).normal;
    assert!(close(n, -DVec3::new(1.0, 0.0, 1.0).normalize(), 1e-12));
    // Radiance check (rtrace): cone r0=0 r1=-1 is a cup, normal (0,-1,1)/√2 at (0,.5,.5).
    let (c, w) = Surface::from_primitive_warn(
        &prim("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0]),
        DVec3::ZERO,
    )
    .unwrap();
    assert!(w.is_some());
    let o = DVec3::new(0.0, 5.0, 0.5);
    let t = c.intersect(o, -DVec3::Y, 1e10).unwrap();
    assert!((t - 4.5).abs() < 1e-12);
    assert!(close(
        c.hit_geom(o, -DVec3::Y, t).normal,
        DVec3::new(0.0, -1.0, 1.0).normalize(),
        1e-12
    ));
    let Surface::Cone(k) = surf("tube", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0]) else {
        panic!("not a cone")
    };
    assert_eq!(k.kind, ConeKind::Cylinder);
    // Areas.
    assert!((cyl.area() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
    assert!((cone.area() - std::f64::consts::PI * 2f64.sqrt()).abs() < 1e-12);

    // Random cones of every kind versus the marching reference.
    let mut rng = Rng(99);
    for case in 0..60 {
        let p0 = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let p1 = p0 + rng.dir() * rng.range(0.5, 2.0);
        let kind = ["cone", "cup", "cylinder", "tube"][case % 4];
        let (r0, r1) = if case % 4 < 2 {
            (rng.range(0.0, 1.0), rng.range(0.2, 1.0))
        } else {
            let r = rng.range(0.2, 1.0);
            (r, r)
        };
        let mut args = vec![p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, r0];
        if case % 4 < 2 {
            args.push(r1);
        }
        let s = surf(kind, &args);
        let axis = (p1 - p0).normalize();
        let len = (p1 - p0).length();
        let f = |p: DVec3| {
            let z = (p - p0).dot(axis);
            if !(0.0..=len).contains(&z) {
                return None;
            }
            let rho = ((p - p0) - axis * z).length();
            Some(rho - (r0 + (r1 - r0) * z / len))
        };
        for _ in 0..40 {
            let org = p0 + rng.dir() * rng.range(0.0, 4.0);
            let aim = p0 + (p1 - p0) * rng.next() + rng.dir() * 0.8;
            let dir = (aim - org).normalize();
            let got = s.intersect(org, dir, 8.0);
            let want = march(f, org, dir, 8.0);
            match (got, want) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() < 1e-6, "{kind}: {a} vs {b}");
                    let g = s.hit_geom(org, dir, a);
                    // Normal: gradient of rho - r(z), flipped for cup/tube.
                    let rel = g.point - p0;
                    let z = rel.dot(axis);
                    let radial = (rel - axis * z).normalize();
                    let mut n = (radial - axis * ((r1 - r0) / len)).normalize();
                    if kind == "cup" || kind == "tube" {
                        n = -n;
                    }
                    assert!(close(g.normal, n, 1e-9), "{kind} normal");
                    assert!((g.normal.length() - 1.0).abs() < 1e-12);
                }
                (None, None) => {}
                // The marcher can miss grazing double roots or hits right at an open end.
                (a, b) => {
                    let t = a.or(b).unwrap();
                    let p = org + dir * t;
                    let z = (p - p0).dot(axis);
                    let grazing = f(p).is_some_and(|v| v.abs() < 1e-6)
                        && march(f, org, dir, t + 1e-3).is_none();
                    assert!(
                        z.abs() < 1e-5 || (z - len).abs() < 1e-5 || grazing || a.is_some(),
                        "{kind}: got {a:?} want {b:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn ring_and_disk() {
    let disk = surf("ring", &[1.0, 1.0, 1.0, 0.0, 0.0, 2.0, 0.0, 1.0]);
    let o = DVec3::new(1.5, 1.0, 5.0);
    let t = disk.intersect(o, -DVec3::Z, 1e10).unwrap();
    assert!((t - 4.0).abs() < 1e-12);
    let g = disk.hit_geom(o, -DVec3::Z, t);
    assert_eq!(g.normal, DVec3::Z);
    assert!((g.uv.1 - 0.5).abs() < 1e-12);
    // Back side still hits; normal not flipped.
    let o2 = DVec3::new(1.5, 1.0, -5.0);
    let t2 = disk.intersect(o2, DVec3::Z, 1e10).unwrap();
    assert_eq!(disk.hit_geom(o2, DVec3::Z, t2).normal, DVec3::Z);
    // Parallel: miss.
    assert!(disk
        .intersect(DVec3::new(-5.0, 1.0, 1.0), DVec3::X, 1e10)
        .is_none());
    // Annulus with swapped radii (Radiance swaps them).
    let ring = surf("ring", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 1.0]);
    assert!(ring
        .intersect(DVec3::new(0.5, 0.0, 1.0), -DVec3::Z, 1e10)
        .is_none());
    assert!(ring
        .intersect(DVec3::new(1.0, 0.0, 1.0), -DVec3::Z, 1e10)
        .is_some());
    assert!(ring
        .intersect(DVec3::new(1.5, 0.0, 1.0), -DVec3::Z, 1e10)
        .is_some());
    assert!(ring
        .intersect(DVec3::new(2.0, 0.0, 1.0), -DVec3::Z, 1e10)
        .is_some());
    assert!(ring
        .intersect(DVec3::new(2.01, 0.0, 1.0), -DVec3::Z, 1e10)
        .is_none());
    assert!((ring.area() - 3.0 * std::f64::consts::PI).abs() < 1e-12);
    assert!(ring.is_flat());
    // Tilted ring bounds are exact.
    let n = DVec3::new(1.0, 0.0, 1.0).normalize();
    let tilt = surf("ring", &[0.0, 0.0, 0.0, n.x, n.y, n.z, 0.0, 1.0]);
    let (lo, hi) = tilt.bounds();
    let h = 0.5f64.sqrt();
    assert!(close(lo, DVec3::new(-h, -1.0, -h), 1e-12) && close(hi, DVec3::new(h, 1.0, h), 1e-12));
}

#[test]
fn polygon_closed_form_and_back_side() {
    let p = surf(
        "polygon",
        &[0.0, 0.0, 2.0, 3.0, 0.0, 2.0, 3.0, 3.0, 2.0, 0.0, 3.0, 2.0],
    );
    let o = DVec3::new(1.0, 1.0, 7.0);
    let d = DVec3::new(0.0, 0.0, -1.0);
    let t = p.intersect(o, d, 1e10).unwrap();
    assert!((t - 5.0).abs() < 1e-12);
    let g = p.hit_geom(o, d, t);
    assert_eq!(g.normal, DVec3::Z);
    assert!((p.area() - 9.0).abs() < 1e-12);
    let t = p
        .intersect(DVec3::new(1.0, 1.0, -1.0), DVec3::Z, 1e10)
        .unwrap();
    assert!((t - 3.0).abs() < 1e-12);
    // Parallel within FTINY: miss.
    let grazing = DVec3::new(1.0, 0.0, -0.5e-6).normalize();
    assert!(p
        .intersect(DVec3::new(-1.0, 1.0, 2.0), grazing, 1e10)
        .is_none());
    // Clockwise order flips the normal.
    let q = surf(
        "polygon",
        &[0.0, 3.0, 2.0, 3.0, 3.0, 2.0, 3.0, 0.0, 2.0, 0.0, 0.0, 2.0],
    );
    assert_eq!(q.hit_geom(o, d, 5.0).normal, -DVec3::Z);
}

// ---------------------------------------------------------------- errors and degenerates

#[test]
fn argument_errors() {
    let z = DVec3::ZERO;
    let bad: &[(&str, &[f64])] = &[
        ("polygon", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
        (
            "polygon",
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
        ),
        ("sphere", &[0.0, 0.0, 1.0]),
        ("sphere", &[0.0, 0.0, 0.0, 0.0]),
        ("bubble", &[0.0, 0.0, 0.0, f64::NAN]),
        ("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, -0.5]),
        ("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0]),
        ("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
        ("cylinder", &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        ("cylinder", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        ("tube", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
        ("ring", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
        ("ring", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, -1.0, 1.0]),
        ("ring", &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        ("ring", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0]),
        ("plastic", &[0.5, 0.5, 0.5, 0.0, 0.0]),
        ("source", &[0.0, 0.0, 1.0, 0.5]),
    ];
    for (ty, args) in bad {
        assert!(
            Surface::from_primitive(&prim(ty, args), z).is_err(),
            "{ty} {args:?} should fail"
        );
    }
    assert!(DistantSource::from_primitive(&prim("source", &[0.0, 0.0, 1.0])).is_err());
    assert!(DistantSource::from_primitive(&prim("source", &[0.0, 0.0, 0.0, 1.0])).is_err());
    let s = DistantSource::from_primitive(&prim("source", &[0.0, 0.0, 3.0, 0.5])).unwrap();
    assert_eq!(s.dir, DVec3::Z);
}

#[test]
fn degenerate_surfaces_never_hit_never_nan() {
    // Zero-area polygons: collinear, all equal.
    let (col, w) = Surface::from_primitive_warn(
        &prim("polygon", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.0, 0.0, 0.0]),
        DVec3::ZERO,
    )
    .unwrap();
    assert!(w.unwrap().contains("zero area"));
    let same = surf("polygon", &[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]);
    let mut rng = Rng(5);
    for _ in 0..2000 {
        let o = DVec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let d = rng.dir();
        assert!(col.intersect(o, d, 1e10).is_none());
        assert!(same.intersect(o, d, 1e10).is_none());
        // Rays straight along the degenerate segment.
        assert!(col
            .intersect(DVec3::new(-1.0, 0.0, 0.0), DVec3::X, 1e10)
            .is_none());
    }
    assert_eq!(col.area(), 0.0);
    let g = col.hit_geom(DVec3::ZERO, DVec3::X, 1.0);
    assert!(g.normal.is_finite() && g.point.is_finite());
    // Near-degenerate cone (tiny radii) and a ray exactly along a cone's axis through its apex.
    let thin = surf("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1e-300, 0.0]);
    let cone = surf("cone", &[0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    for _ in 0..2000 {
        let o = DVec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let d = rng.dir();
        if let Some(t) = thin.intersect(o, d, 1e10) {
            assert!(t.is_finite());
            assert!(thin.hit_geom(o, d, t).normal.is_finite());
        }
    }
    // Along the axis: passes through the apex (measure-zero contact); whatever happens, no NaN.
    if let Some(t) = cone.intersect(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z, 1e10) {
        let g = cone.hit_geom(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z, t);
        assert!(t.is_finite() && g.normal.is_finite());
    }
    // Garbage rays: zero and NaN directions.
    let sph = surf("sphere", &[0.0, 0.0, 0.0, 1.0]);
    for s in [&sph, &cone, &col, &thin] {
        assert!(s
            .intersect(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, 1e10)
            .is_none());
        assert!(s
            .intersect(DVec3::new(0.0, 0.0, 5.0), DVec3::splat(f64::NAN), 1e10)
            .is_none());
    }
}

// ---------------------------------------------------------------- holes and concavity

#[test]
fn concave_polygon_with_seam_hole() {
    // An L-shape (outer, CCW) with a square hole joined to vertex 0 by a seam.
    //   outer: (0,0) (6,0) (6,3) (3,3) (3,6) (0,6); hole: (1,1)..(2,2) traversed clockwise.
    let outer = [
        (0.0, 0.0),
        (6.0, 0.0),
        (6.0, 3.0),
        (3.0, 3.0),
        (3.0, 6.0),
        (0.0, 6.0),
    ];
    let hole = [(1.0, 1.0), (1.0, 2.0), (2.0, 2.0), (2.0, 1.0)];
    let mut pts: Vec<(f64, f64)> = outer.to_vec();
    pts.push((0.0, 0.0));
    pts.extend_from_slice(&hole);
    pts.push((1.0, 1.0));
    // Tilted plane z = 0.3 x + 0.2 y.
    let lift = |x: f64, y: f64| DVec3::new(x, y, 0.3 * x + 0.2 * y);
    let args: Vec<f64> = pts
        .iter()
        .flat_map(|&(x, y)| lift(x, y).to_array())
        .collect();
    let s = surf("polygon", &args);
    let Surface::Polygon(poly) = &s else {
        panic!("not a polygon")
    };
    let poly = poly.r();
    let area = 27.0 - 1.0; // L (36 - 9) minus hole
    let n = DVec3::new(-0.3, -0.2, 1.0);
    assert!((poly.area - area * n.length()).abs() < 1e-9);
    assert!(close(poly.normal, n.normalize(), 1e-12));
    let analytic = |x: f64, y: f64| {
        let in_l = (0.0..=6.0).contains(&x) && (0.0..=6.0).contains(&y) && !(x > 3.0 && y > 3.0);
        let in_hole = x > 1.0 && x < 2.0 && y > 1.0 && y < 2.0;
        in_l && !in_hole
    };
    let mut checked = 0;
    for i in 0..=140 {
        for j in 0..=140 {
            let x = -0.5 + i as f64 * 0.05 + 0.0123;
            let y = -0.5 + j as f64 * 0.05 + 0.0071;
            // Stay away from edges and from the seam line y = x (both count as inside).
            let edge_d = [
                x,
                y,
                (x - 6.0),
                (y - 6.0),
                x - 3.0,
                y - 3.0,
                x - 1.0,
                x - 2.0,
                y - 1.0,
                y - 2.0,
            ]
            .iter()
            .map(|v| v.abs())
            .fold(f64::INFINITY, f64::min);
            if edge_d < 1e-3 || ((x - y).abs() < 1e-3 && x < 1.0) {
                continue;
            }
            let p = lift(x, y);
            let o = p + DVec3::new(0.1, -0.2, 3.0);
            let d = (p - o).normalize();
            let hit = s.intersect(o, d, 1e10).is_some();
            assert_eq!(hit, analytic(x, y), "({x}, {y})");
            checked += 1;
        }
    }
    assert!(checked > 15000);
    // Points on the seam, on the hole boundary and on outer edges count as inside.
    for (x, y) in [
        (0.5, 0.5),
        (1.5, 1.0),
        (2.0, 1.5),
        (6.0, 1.0),
        (3.0, 4.0),
        (3.0, 3.0),
    ] {
        assert!(poly.contains(lift(x, y)), "edge point ({x}, {y})");
    }
}

// ---------------------------------------------------------------- cracks

/// A flat grid of quads (each split into two triangles when `tris`), z = 0.
fn grid_scene(n: usize, tris: bool, origin: DVec3, base: DVec3) -> Vec<Surface> {
    let mut out = vec![];
    for i in 0..n {
        for j in 0..n {
            let p = |a: usize, b: usize| {
                base + DVec3::new((i + a) as f64 * 0.37, (j + b) as f64 * 0.37, 0.0)
            };
            let quad = [p(0, 0), p(1, 0), p(1, 1), p(0, 1)];
            let polys: Vec<Vec<DVec3>> = if tris {
                vec![
                    vec![quad[0], quad[1], quad[2]],
                    vec![quad[0], quad[2], quad[3]],
                ]
            } else {
                vec![quad.to_vec()]
            };
            for v in polys {
                let args: Vec<f64> = v.iter().flat_map(|p| p.to_array()).collect();
                out.push(Surface::from_primitive(&prim("polygon", &args), origin).unwrap());
            }
        }
    }
    out
}

fn brute(surfs: &[Surface], o: DVec3, d: DVec3, tmax: f64) -> Option<(usize, f64)> {
    let hits = surfs
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.intersect(o, d, tmax).map(|t| (i, t)));
    select_closest(hits, tmax, |a, b| a > b)
}

#[test]
fn no_cracks_between_adjacent_polygons() {
    for (tris, base, origin) in [
        (false, DVec3::ZERO, DVec3::ZERO),
        (true, DVec3::ZERO, DVec3::ZERO),
        (true, DVec3::new(1e6, -1e6, 1e6), DVec3::new(1e6, -1e6, 1e6)),
        (true, DVec3::new(1e6, -1e6, 1e6), DVec3::ZERO),
    ] {
        let surfs = grid_scene(6, tris, origin, base);
        let bvh = Bvh::build(&surfs.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
        let rel = base - origin;
        let mut rng = Rng(11);
        let mut n = 0;
        // Aim at points on grid lines, on diagonals and at vertices, from many directions.
        for k in 0..4000 {
            let i = (rng.next() * 6.0) as usize;
            let j = (rng.next() * 6.0) as usize;
            let f = rng.next();
            let (a, b) = match k % 4 {
                0 => (i as f64, j as f64 + f),     // vertical grid line
                1 => (i as f64 + f, j as f64),     // horizontal grid line
                2 => (i as f64 + f, j as f64 + f), // diagonal
                _ => (i as f64, j as f64),         // vertex
            };
            let target = rel + DVec3::new(a * 0.37, b * 0.37, 0.0);
            // Keep inside the grid (outer boundary excluded: nothing beyond it).
            if a <= 0.0 || b <= 0.0 || a >= 6.0 || b >= 6.0 {
                continue;
            }
            let mut d = rng.dir();
            if d.z.abs() < 0.02 {
                continue;
            }
            if d.z > 0.0 {
                d = -d;
            }
            let o = target - d * rng.range(0.1, 5.0);
            let want = brute(&surfs, o, d, 1e10);
            assert!(want.is_some(), "crack at {a},{b} dir {d}");
            let got = bvh.closest(o, d, 1e10, |i| surfs[i].intersect(o, d, 1e10), |a, b| a > b);
            assert_eq!(got, want);
            n += 1;
        }
        assert!(n > 2000);
    }
}

/// A closed box room (6 inward-facing polygons), a sphere and a cone inside, at `base`.
fn room_scene(base: DVec3, origin: DVec3) -> Vec<Surface> {
    let (x, y, z) = (4.0, 3.0, 2.5);
    let v = |a: f64, b: f64, c: f64| base + DVec3::new(a, b, c);
    let faces = [
        [
            v(0.0, 0.0, 0.0),
            v(0.0, y, 0.0),
            v(x, y, 0.0),
            v(x, 0.0, 0.0),
        ], // floor, normal +z
        [v(0.0, 0.0, z), v(x, 0.0, z), v(x, y, z), v(0.0, y, z)], // ceiling, -z
        [
            v(0.0, 0.0, 0.0),
            v(x, 0.0, 0.0),
            v(x, 0.0, z),
            v(0.0, 0.0, z),
        ], // y = 0, +y
        [v(0.0, y, 0.0), v(0.0, y, z), v(x, y, z), v(x, y, 0.0)], // y = Y, -y
        [
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, z),
            v(0.0, y, z),
            v(0.0, y, 0.0),
        ], // x = 0, +x
        [v(x, 0.0, 0.0), v(x, y, 0.0), v(x, y, z), v(x, 0.0, z)], // x = X, -x
    ];
    let mut out: Vec<Surface> = faces
        .iter()
        .map(|f| {
            let args: Vec<f64> = f.iter().flat_map(|p| p.to_array()).collect();
            Surface::from_primitive(&prim("polygon", &args), origin).unwrap()
        })
        .collect();
    let c = v(1.2, 1.1, 1.0);
    out.push(Surface::from_primitive(&prim("sphere", &[c.x, c.y, c.z, 0.6]), origin).unwrap());
    let a = v(3.0, 2.0, 0.2);
    let b = v(3.0, 2.3, 1.8);
    out.push(
        Surface::from_primitive(
            &prim("cone", &[a.x, a.y, a.z, b.x, b.y, b.z, 0.5, 0.1]),
            origin,
        )
        .unwrap(),
    );
    out
}

/// Random walk of specular bounces inside the room; returns the sequence of (index, t).
fn walk(surfs: &[Surface], bvh: &Bvh, start: DVec3, seed: u64) -> Vec<(usize, f64)> {
    let mut rng = Rng(seed);
    let mut o = start;
    let mut d = rng.dir();
    let mut path = vec![];
    for _ in 0..300 {
        let hit = bvh.closest(o, d, 1e10, |i| surfs[i].intersect(o, d, 1e10), |a, b| a > b);
        let Some((i, t)) = hit else {
            panic!("ray escaped the closed room after {} bounces", path.len());
        };
        assert!(t > FTINY, "self hit");
        path.push((i, t));
        let g = surfs[i].hit_geom(o, d, t);
        // New random direction on the side the ray came from; start exactly at the hit point.
        let n = if g.normal.dot(d) < 0.0 {
            g.normal
        } else {
            -g.normal
        };
        let mut nd = rng.dir();
        if nd.dot(n) < 0.0 {
            nd = -nd;
        }
        o = g.point;
        d = nd;
    }
    path
}

#[test]
fn far_from_origin_scene() {
    let shift = DVec3::new(1e6, -1e6, 1e6);
    let near = room_scene(DVec3::ZERO, DVec3::new(2.0, 1.5, 1.25));
    let far = room_scene(shift, shift + DVec3::new(2.0, 1.5, 1.25));
    let far0 = room_scene(shift, DVec3::ZERO);
    let bn = Bvh::build(&near.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    let bf = Bvh::build(&far.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    let bf0 = Bvh::build(&far0.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    let start_rel = DVec3::new(0.5, -0.8, 0.3); // relative to the room centre
    for seed in 1..30 {
        let pn = walk(&near, &bn, start_rel, seed);
        let pf = walk(&far, &bf, start_rel, seed);
        // Same relative geometry (up to the rounding of 1e6 + x): same walk for a while.
        let same = pn
            .iter()
            .zip(&pf)
            .take_while(|(a, b)| a.0 == b.0 && (a.1 - b.1).abs() < 1e-6)
            .count();
        assert!(
            same >= 20,
            "seed {seed}: walks diverged after {same} bounces"
        );
        // Origin at 0 with coordinates near 1e6: still closed, no self hits (walk asserts).
        let p0 = walk(
            &far0,
            &bf0,
            shift + DVec3::new(2.0, 1.5, 1.25) + start_rel,
            seed,
        );
        assert_eq!(p0.len(), 300);
    }
}

#[test]
fn rays_along_edges_and_grazing() {
    let room = room_scene(DVec3::ZERO, DVec3::ZERO);
    let bvh = Bvh::build(&room.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    // Rays from inside aimed exactly at room edges and corners must hit a wall.
    let mut rng = Rng(3);
    let corners = [0.0, 4.0];
    for _ in 0..3000 {
        let target = match (rng.next() * 3.0) as usize {
            0 => DVec3::new(
                rng.range(0.0, 4.0),
                [0.0, 3.0][(rng.next() * 2.0) as usize],
                [0.0, 2.5][(rng.next() * 2.0) as usize],
            ),
            1 => DVec3::new(
                corners[(rng.next() * 2.0) as usize],
                rng.range(0.0, 3.0),
                [0.0, 2.5][(rng.next() * 2.0) as usize],
            ),
            _ => DVec3::new(
                corners[(rng.next() * 2.0) as usize],
                [0.0, 3.0][(rng.next() * 2.0) as usize],
                rng.range(0.0, 2.5),
            ),
        };
        let o = DVec3::new(
            rng.range(0.1, 3.9),
            rng.range(0.1, 2.9),
            rng.range(0.1, 2.4),
        );
        let d = (target - o).normalize();
        let hit = bvh.closest(o, d, 1e10, |i| room[i].intersect(o, d, 1e10), |a, b| a > b);
        assert!(hit.is_some(), "escaped through an edge toward {target}");
    }
    // A ray running exactly inside the floor plane: parallel to the floor (miss) but must hit
    // the far wall.
    let o = DVec3::new(0.5, 1.0, 0.0);
    let hit = bvh.closest(
        o,
        DVec3::X,
        1e10,
        |i| room[i].intersect(o, DVec3::X, 1e10),
        |a, b| a > b,
    );
    let (i, t) = hit.unwrap();
    assert_eq!(i, 5);
    assert!((t - 3.5).abs() < 1e-12);
    // Grazing the sphere (tangent) still returns a finite answer close to the tangent point.
    let s = &room[6];
    let o = DVec3::new(1.2 + 0.6, -5.0, 1.0);
    if let Some(t) = s.intersect(o, DVec3::Y, 1e10) {
        assert!((t - 6.1).abs() < 1e-3);
    }
}

// ---------------------------------------------------------------- BVH versus brute force

fn random_scene(rng: &mut Rng, n: usize) -> Vec<Surface> {
    let mut out = vec![];
    while out.len() < n {
        let c = DVec3::new(
            rng.range(-10.0, 10.0),
            rng.range(-10.0, 10.0),
            rng.range(-10.0, 10.0),
        );
        let s = match (rng.next() * 5.0) as usize {
            0 => {
                let r = rng.range(0.1, 2.0);
                prim(
                    if rng.next() < 0.5 { "sphere" } else { "bubble" },
                    &[c.x, c.y, c.z, r],
                )
            }
            1 => {
                let e = c + rng.dir() * rng.range(0.2, 3.0);
                let kinds = ["cone", "cup"];
                prim(
                    kinds[(rng.next() * 2.0) as usize],
                    &[
                        c.x,
                        c.y,
                        c.z,
                        e.x,
                        e.y,
                        e.z,
                        rng.range(0.0, 1.0),
                        rng.range(0.1, 1.0),
                    ],
                )
            }
            2 => {
                let e = c + rng.dir() * rng.range(0.2, 3.0);
                prim(
                    "cylinder",
                    &[c.x, c.y, c.z, e.x, e.y, e.z, rng.range(0.1, 1.0)],
                )
            }
            3 => {
                let nrm = rng.dir();
                prim(
                    "ring",
                    &[
                        c.x,
                        c.y,
                        c.z,
                        nrm.x,
                        nrm.y,
                        nrm.z,
                        rng.range(0.0, 0.5),
                        rng.range(0.6, 2.0),
                    ],
                )
            }
            _ => {
                let (u, v) = (rng.dir(), rng.dir());
                let k = 3 + (rng.next() * 4.0) as usize;
                let mut args = vec![];
                for m in 0..k {
                    let a = std::f64::consts::TAU * m as f64 / k as f64;
                    let p = c + (u * a.cos() + v * a.sin()) * rng.range(0.5, 3.0);
                    args.extend(p.to_array());
                }
                prim("polygon", &args)
            }
        };
        if let Ok(s) = Surface::from_primitive(&s, DVec3::new(0.5, -0.5, 0.25)) {
            out.push(s);
        }
    }
    // Exact duplicates to exercise the coincident-surface rule.
    for k in 0..20 {
        let s = out[k * 7].clone();
        out.push(s);
    }
    out
}

#[test]
fn bvh_matches_brute_force() {
    let mut rng = Rng(2024);
    let surfs = random_scene(&mut rng, 600);
    let bounds: Vec<_> = surfs.iter().map(|s| s.bounds()).collect();
    let bvh = Bvh::build(&bounds, FTINY);
    assert_eq!(bvh.len(), surfs.len());
    let prefs: [fn(usize, usize) -> bool; 3] = [|a, b| a > b, |a, b| a < b, |_, _| false];
    let mut hits = 0;
    for k in 0..6000 {
        let o = if k % 3 == 0 {
            // From outside the scene, far away.
            rng.dir() * [30.0, 1000.0, 1e6][k % 9 / 3] * rng.range(1.0, 2.0)
        } else {
            DVec3::new(
                rng.range(-11.0, 11.0),
                rng.range(-11.0, 11.0),
                rng.range(-11.0, 11.0),
            )
        };
        let d = if k % 3 == 0 {
            (DVec3::new(
                rng.range(-8.0, 8.0),
                rng.range(-8.0, 8.0),
                rng.range(-8.0, 8.0),
            ) - o)
                .normalize()
        } else if k % 7 == 1 {
            // Axis-aligned (with negative zeros) and nearly axis-aligned directions.
            let axes = [
                DVec3::X,
                DVec3::Y,
                DVec3::Z,
                -DVec3::X,
                -DVec3::Y,
                -DVec3::Z,
            ];
            let a = axes[(rng.next() * 6.0) as usize];
            let tiny = [0.0, 1e-30, -1e-12, 1e-9, -1e-7, 3e-6][(rng.next() * 6.0) as usize];
            (a + DVec3::new(tiny, -tiny, 0.5 * tiny)).normalize()
        } else {
            rng.dir()
        };
        let tmax = if k % 5 == 0 {
            rng.range(1.0, 20.0)
        } else {
            1e10
        };
        let prefer = prefs[k % 3];
        let want = {
            let hits = surfs
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.intersect(o, d, tmax).map(|t| (i, t)));
            select_closest(hits, tmax, prefer)
        };
        let got = bvh.closest(o, d, tmax, |i| surfs[i].intersect(o, d, tmax), prefer);
        assert_eq!(got, want, "ray {k}");
        if let Some((i, t)) = got {
            hits += 1;
            // Continue from the hit point exactly (secondary ray).
            let g = surfs[i].hit_geom(o, d, t);
            let d2 = rng.dir();
            let want2 = {
                let hits = surfs
                    .iter()
                    .enumerate()
                    .filter_map(|(j, s)| s.intersect(g.point, d2, 1e10).map(|t| (j, t)));
                select_closest(hits, 1e10, prefer)
            };
            let got2 = bvh.closest(
                g.point,
                d2,
                1e10,
                |j| surfs[j].intersect(g.point, d2, 1e10),
                prefer,
            );
            assert_eq!(got2, want2, "secondary ray {k}");
            // Candidates include every surface the ray really hits.
            let mut cand = vec![false; surfs.len()];
            bvh.candidates(o, d, tmax, |j| cand[j] = true);
            for (j, s) in surfs.iter().enumerate() {
                if s.intersect(o, d, tmax).is_some() {
                    assert!(cand[j], "surface {j} hit but not a candidate");
                }
            }
        }
    }
    assert!(hits > 1500, "only {hits} hits");
}

#[test]
fn duplicates_resolved_by_prefer() {
    let a = surf(
        "polygon",
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
    );
    let surfs = [a.clone(), a.clone(), a];
    let bvh = Bvh::build(&surfs.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    let o = DVec3::new(0.5, 0.5, 1.0);
    let d = -DVec3::Z;
    let f = |i: usize| surfs[i].intersect(o, d, 1e10);
    assert_eq!(bvh.closest(o, d, 1e10, f, |a, b| a > b).unwrap().0, 2);
    assert_eq!(bvh.closest(o, d, 1e10, f, |a, b| a < b).unwrap().0, 0);
    assert_eq!(bvh.closest(o, d, 1e10, f, |a, _| a == 1).unwrap().0, 1);
    assert_eq!(bvh.closest(o, d, 1e10, f, |_, _| false).unwrap().0, 0);
}

// ---------------------------------------------------------------- versus Radiance

#[test]
fn compare_with_rtrace() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let bin = "/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin";
    if !std::path::Path::new(&format!("{bin}/rtrace")).exists() {
        eprintln!("Radiance not installed: skipping");
        return;
    }
    let scene = "void plastic m 0 0 5 .5 .5 .5 0 0\n\
        m sphere s 0 0 4 10 0 0 1.5\n\
        m bubble b 0 0 4 0 10 0 1.2\n\
        m cone c 0 0 8 -10 0 -1 -10 0.5 1 1.3 0.4\n\
        m cup u 0 0 8 0 -10 -1 0.3 -10 1 0.4 1.1\n\
        m cylinder y 0 0 7 0 0 9 0.5 0.3 11 1.0\n\
        m tube t 0 0 7 0 0 -9 0.5 0.3 -11 1.0\n\
        m ring r 0 0 8 7 7 0 1 1 1 0.3 1.4\n\
        m polygon p 0 0 15 -7 -7 -1 -6 -8 0 -7 -7 1 -8 -6 0.5 -7.5 -6 -0.5\n";
    let dir = tempfile::tempdir().unwrap();
    let rad = dir.path().join("s.rad");
    let oct = dir.path().join("s.oct");
    std::fs::write(&rad, scene).unwrap();
    let out = Command::new(format!("{bin}/oconv"))
        .arg(&rad)
        .output()
        .unwrap();
    if !out.status.success() {
        eprintln!("oconv failed: skipping");
        return;
    }
    std::fs::write(&oct, out.stdout).unwrap();
    let origin = DVec3::new(0.3, -0.2, 0.1);
    let mut surfs = vec![];
    for line in scene.lines().skip(1) {
        let w: Vec<&str> = line.split_whitespace().collect();
        let args: Vec<f64> = w[6..].iter().map(|x| x.parse().unwrap()).collect();
        surfs.push(Surface::from_primitive(&prim(w[1], &args), origin).unwrap());
    }
    let targets = [
        DVec3::new(10.0, 0.0, 0.0),
        DVec3::new(0.0, 10.0, 0.0),
        DVec3::new(-10.0, 0.2, 0.0),
        DVec3::new(0.1, -10.0, 0.0),
        DVec3::new(0.0, 0.4, 10.0),
        DVec3::new(0.0, 0.4, -10.0),
        DVec3::new(7.0, 7.0, 0.0),
        DVec3::new(-7.0, -7.0, 0.0),
    ];
    let mut rng = Rng(77);
    let mut rays = vec![];
    for tgt in targets {
        for _ in 0..30 {
            let aim = tgt + rng.dir() * rng.range(0.0, 1.2);
            let o = tgt + rng.dir() * rng.range(3.0, 6.0);
            rays.push((o, (aim - o).normalize()));
        }
    }
    let mut child = Command::new(format!("{bin}/rtrace"))
        .args(["-h-", "-ab", "0", "-oLpN"])
        .arg(&oct)
        .env("RAYPATH", format!(".:{bin}/../lib"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    {
        let mut stdin = child.stdin.take().unwrap();
        for (o, d) in &rays {
            writeln!(stdin, "{} {} {} {} {} {}", o.x, o.y, o.z, d.x, d.y, d.z).unwrap();
        }
    }
    let out = child.wait_with_output().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), rays.len());
    let bvh = Bvh::build(&surfs.iter().map(|s| s.bounds()).collect::<Vec<_>>(), FTINY);
    let mut compared = 0;
    for ((o, d), line) in rays.iter().zip(lines) {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let ro = *o - origin;
        let got = bvh.closest(
            ro,
            *d,
            1e10,
            |i| surfs[i].intersect(ro, *d, 1e10),
            |a, b| a > b,
        );
        if v[0] >= 1e9 {
            assert!(got.is_none(), "rtrace missed, we hit: {o} {d} {got:?}");
            continue;
        }
        let (i, t) = got.unwrap_or_else(|| panic!("we missed, rtrace hit: {o} {d} {line}"));
        let g = surfs[i].hit_geom(ro, *d, t);
        assert!((t - v[0]).abs() < 1e-4 * v[0].max(1.0), "t {t} vs {}", v[0]);
        let p = DVec3::new(v[1], v[2], v[3]);
        assert!(close(g.point + origin, p, 1e-4 * v[0].max(1.0)), "point");
        let n = DVec3::new(v[4], v[5], v[6]);
        assert!(
            close(g.normal, n, 1e-4),
            "normal {} vs {n} on {i}",
            g.normal
        );
        compared += 1;
    }
    assert!(compared > 100, "only {compared} hits compared");
}

#[test]
fn polygon_new_direct() {
    let (p, w) = PolygonBuf::new(vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::new(1.0, 1.0, 0.3),
        DVec3::Y,
    ])
    .unwrap();
    assert!(w.unwrap().contains("non-planar"));
    assert!(p.rec.area > 0.0);
    assert!(PolygonBuf::new(vec![DVec3::ZERO, DVec3::X]).is_err());
}

#[test]
fn many_identical_and_nested_boxes() {
    // Pathological inputs for the builder: identical boxes and deeply nested boxes.
    // (Kept small: obvhs's PLOC builder is quadratic-ish on such input, ~1 s here in debug.)
    let same = vec![(DVec3::ZERO, DVec3::ONE); 1000];
    let bvh = Bvh::build(&same, FTINY);
    let mut n = 0;
    bvh.candidates(DVec3::splat(0.5), DVec3::X, 1e10, |_| n += 1);
    assert_eq!(n, 1000);
    let got = bvh.closest(
        DVec3::new(-1.0, 0.5, 0.5),
        DVec3::X,
        1e10,
        |i| Some(1.0 + i as f64 * 1e-3),
        |_, _| false,
    );
    assert_eq!(got, Some((0, 1.0)));
    let nested: Vec<_> = (0..1000)
        .map(|i| {
            let s = 1.001f64.powi(i);
            (DVec3::splat(-s), DVec3::splat(s))
        })
        .collect();
    let bvh = Bvh::build(&nested, FTINY);
    let mut n = 0;
    bvh.candidates(DVec3::ZERO, DVec3::Y, 1e10, |_| n += 1);
    assert_eq!(n, 1000);
}
