//! The pattern frame: where a pattern, texture or mixture evaluates its expressions.
//!
//! A modifier's optional transform (`-t -rx -ry -rz -s -mx -my -mz -i`, after its
//! expressions) places pattern coordinates in the world; the renderer maps each hit the
//! other way, world → pattern. The ray variables (`$1..$27`: `Dx Dy Dz Nx Ny Nz Px Py Pz T
//! Rdot S Tx Ty Tz Ix..Kz Ts Lu Lv`) are the hit seen in that frame
//! (radiance-formats.md §1.8): directions are unit vectors, lengths are multiplied by the
//! world → pattern scale `S`. A hit through an instance or mesh is first taken into that
//! object's own frame ([`ShadingPoint::transform`]).

use crate::render::shading::ShadingPoint;
use crate::scene::transform::{parse_transform, Transform};
use glam::{DMat4, DVec3};

/// Number of ray channels (`$1..$27`).
pub const CHANNELS: usize = 27;

/// Channel masks (bit `c` for channel index `c`) of [`PatternFrame::channels_for`]: the
/// direction `Dx Dy Dz`, the normal `Nx Ny Nz`, the point `Px Py Pz`, the frame's axes
/// `Tx … Kz`.
const DIR: u32 = 0b111;
const NORMAL: u32 = 0b111 << 3;
const POINT: u32 = 0b111 << 6;
const AXES: u32 = 0xfff << 12;

/// The channels that depend on where the hit lies along the ray: the point, the path's
/// length `T` and the ray's `Ts`.
pub const ALONG_RAY: u32 = POINT | 1 << 9 | 1 << 24;

/// `Tx Ty Tz` (the world origin) and the unit axes `Ix … Kz` of a world → pattern matrix.
fn axes(m: &DMat4) -> [f64; 12] {
    let t0 = m.transform_point3(DVec3::ZERO);
    let axis = |v: DVec3| m.transform_vector3(v).normalize_or_zero();
    let (i, j, k) = (axis(DVec3::X), axis(DVec3::Y), axis(DVec3::Z));
    [
        t0.x, t0.y, t0.z, i.x, i.y, i.z, j.x, j.y, j.z, k.x, k.y, k.z,
    ]
}

/// A modifier's world → pattern mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct PatternFrame {
    /// Pattern → world (the transform as written), None for the identity.
    forward: Option<DMat4>,
    /// World → pattern.
    inverse: DMat4,
    /// World → pattern scale (`-s 2` gives 0.5).
    scale: f64,
    /// `Tx Ty Tz Ix … Kz` of `inverse` (the same at every hit of an untransformed object).
    axes: [f64; 12],
}

impl Default for PatternFrame {
    fn default() -> Self {
        PatternFrame::identity()
    }
}

impl PatternFrame {
    /// No transform: pattern coordinates are world coordinates.
    pub fn identity() -> PatternFrame {
        PatternFrame::new(None, DMat4::IDENTITY, 1.0)
    }

    fn new(forward: Option<DMat4>, inverse: DMat4, scale: f64) -> PatternFrame {
        PatternFrame {
            forward,
            inverse,
            scale,
            axes: axes(&inverse),
        }
    }

    /// The frame of a transform (pattern → world as `xf` maps).
    pub fn from_transform(xf: &Transform) -> Result<PatternFrame, String> {
        let m = xf.matrix();
        let inverse = m.inverse();
        if !(inverse.is_finite() && xf.scale().is_finite() && xf.scale() > 0.0) {
            return Err("singular transform".to_string());
        }
        Ok(PatternFrame::new(Some(m), inverse, 1.0 / xf.scale()))
    }

    /// The frame given by a primitive's string arguments after its fixed ones: empty → the
    /// identity; otherwise every remaining word must belong to the transform (Radiance's
    /// "bad transform" otherwise).
    pub fn from_words(words: &[String]) -> Result<PatternFrame, String> {
        if words.is_empty() {
            return Ok(PatternFrame::identity());
        }
        let (xf, used) = parse_transform(words)?;
        if used != words.len() {
            return Err(format!("bad transform at word '{}'", words[used]));
        }
        PatternFrame::from_transform(&xf)
    }

    /// The world → pattern scale `S`.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The world → pattern matrix and scale at a shading point (through the hit object's
    /// own transform first, when it has one).
    fn to_pattern(&self, sp: &ShadingPoint) -> (DMat4, f64) {
        match sp.transform {
            None => (self.inverse, self.scale),
            Some(obj) => {
                let local = obj.inverse();
                (self.inverse * local, self.scale / obj.scale())
            }
        }
    }

    /// The ray channels of `mask` (bit `c` for channel index `c`) at `sp`; the others are
    /// 0. A pattern's pure expression reads a few channels (an ies2rad luminaire's
    /// `src_theta` and `flatcorr`: `Dz` and `Rdot`), and the transform of the point, the
    /// normal and the frame's axes are then not computed.
    pub fn channels_for(&self, sp: &ShadingPoint, mask: u32) -> [f64; CHANNELS] {
        let mut c = [0.0; CHANNELS];
        self.channels_into(sp, mask, &mut c);
        c
    }

    /// [`PatternFrame::channels_for`] written into `c`, whose channels outside `mask` (and
    /// those always computed) keep what they held.
    pub fn channels_into(&self, sp: &ShadingPoint, mask: u32, c: &mut [f64; CHANNELS]) {
        // Direction, normal and point; axes. The lengths, Rdot, the scale and (u, v) cost
        // a product at most, and are always computed.
        // No transform at all: the hit as it is.
        let plain = self.forward.is_none() && sp.transform.is_none();
        // The frame's own matrix is borrowed, not copied, unless the hit object has a
        // transform of its own ([`PatternFrame::to_pattern`]).
        let through;
        let (m, s) = match sp.transform {
            _ if plain => (&self.inverse, 1.0),
            None => (&self.inverse, self.scale),
            Some(_) => {
                through = self.to_pattern(sp);
                (&through.0, through.1)
            }
        };
        let unit = |v: DVec3| m.transform_vector3(v) / s;
        if mask & DIR != 0 {
            let d = if plain { sp.dir } else { unit(sp.dir) };
            c[..3].copy_from_slice(&d.to_array());
        }
        if mask & NORMAL != 0 {
            let n = if plain {
                sp.hit.normal
            } else {
                unit(sp.hit.normal)
            };
            c[3..6].copy_from_slice(&n.to_array());
        }
        if mask & POINT != 0 {
            let p = if plain {
                sp.world_point()
            } else {
                m.transform_point3(sp.world_point())
            };
            c[6..9].copy_from_slice(&p.to_array());
        }
        if mask & AXES != 0 {
            let a = match sp.transform {
                None => self.axes,
                Some(_) => axes(m),
            };
            c[12..24].copy_from_slice(&a);
        }
        let (lu, lv) = sp.uv.map(|[u, v]| (u, v)).unwrap_or((0.0, 0.0));
        c[9] = sp.path_len * s;
        c[10] = (-sp.dir.dot(sp.hit.normal)).clamp(-1.0, 1.0);
        c[11] = s;
        c[24] = sp.ray_len * s;
        c[25] = lu;
        c[26] = lv;
    }

    /// The ray channels `$1..$27` at `sp` (index 0 is `$1`).
    pub fn channels(&self, sp: &ShadingPoint) -> [f64; CHANNELS] {
        self.channels_for(sp, u32::MAX)
    }

    /// A world direction in the pattern frame, unit length for a unit `v` (a BRDF
    /// material's light direction `lx ly lz`, its perturbed normal `NxP NyP NzP`).
    pub fn direction_to_pattern(&self, sp: &ShadingPoint, v: DVec3) -> DVec3 {
        let (m, s) = self.to_pattern(sp);
        m.transform_vector3(v) / s
    }

    /// A vector given in the pattern frame (a texture's perturbation) in world
    /// coordinates: the forward transform divided by its scale (through the hit object's
    /// transform, when it has one).
    pub fn vector_to_world(&self, sp: &ShadingPoint, v: DVec3) -> DVec3 {
        let w = match self.forward {
            None => v,
            Some(f) => f.transform_vector3(v) * self.scale,
        };
        match sp.transform {
            None => w,
            Some(obj) => obj.vector(w) / obj.scale(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::ray::{Hit, Ray, MAX_ANTIMATTER};

    /// The verified case of radiance-formats.md §1.8: a plane z = 0, a ray from
    /// (0.5, 0.25, 1) straight down.
    fn channels(words: &str) -> [f64; CHANNELS] {
        let words: Vec<String> = words.split_whitespace().map(String::from).collect();
        let f = PatternFrame::from_words(&words).unwrap();
        let ray = Ray::primary(DVec3::new(0.5, 0.25, 1.0), -DVec3::Z, f64::INFINITY);
        let hit = Hit {
            obj: 0,
            inst: crate::render::ray::NO_INST,
            t: 1.0,
            point: DVec3::new(0.5, 0.25, 0.0),
            normal: DVec3::Z,
            back: false,
            flat: true,
            material: None,
            antimatter: [None; MAX_ANTIMATTER],
        };
        f.channels(&ShadingPoint::new(&ray, &hit, DVec3::ZERO))
    }

    fn near(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-4)
    }

    #[test]
    fn the_verified_pattern_frames() {
        let p = |c: [f64; CHANNELS], add: f64| [c[6] + add, c[7] + add, c[8] + add];
        assert!(near(p(channels("-t 1 2 3"), 5.0), [4.5, 3.25, 2.0]));
        assert!(near(p(channels("-rz 90 -t 1 2 3"), 5.0), [3.25, 5.5, 2.0]));
        assert!(near(p(channels("-t 1 2 3 -rz 90"), 5.0), [4.25, 2.5, 2.0]));
        let c = channels("-rz 90 -t 1 2 3");
        assert!(near(
            [c[12] + 5.0, c[13] + 5.0, c[14] + 5.0],
            [3.0, 6.0, 2.0]
        ));
        let c = channels("-rz 90 -t 1 2 3 -s 2");
        assert!(near([c[11], c[15] + 2.0, c[16] + 2.0], [0.5, 2.0, 1.0]));
        assert!(near(p(channels("-s 2"), 0.0), [0.25, 0.125, 0.0]));
        assert!(near(p(channels("-mx"), 10.0), [9.5, 10.25, 10.0]));
        let c = channels("-rx 90");
        assert!(near([c[0] + 2.0, c[1] + 2.0, c[2] + 2.0], [2.0, 1.0, 2.0]));
        let c = channels("-s 3");
        assert!(near(
            [c[9], c[10] + 2.0, c[24] + 3.0],
            [1.0 / 3.0, 3.0, 1.0 / 3.0 + 3.0]
        ));
        let c = channels("");
        assert!(near([c[6] + 1.0, c[7] + 1.0, c[8] + 1.0], [1.5, 1.25, 1.0]));
    }

    #[test]
    fn channels_for_a_mask_are_the_channels() {
        let w = |s: &str| s.split_whitespace().map(String::from).collect::<Vec<_>>();
        let (object, _) = parse_transform(&w("-rx 30 -s 1.5 -t 2 0 -1")).unwrap();
        let ray = Ray::primary(
            DVec3::new(0.3, -0.2, 2.0),
            DVec3::new(0.1, 0.2, -1.0).normalize(),
            9.0,
        );
        let hit = Hit {
            obj: 0,
            inst: crate::render::ray::NO_INST,
            t: 1.7,
            point: DVec3::new(0.47, 0.14, 0.3),
            normal: DVec3::new(0.0, 0.6, 0.8),
            back: false,
            flat: true,
            material: None,
            antimatter: [None; MAX_ANTIMATTER],
        };
        for words in ["", "-t 1 2 3", "-rz 90 -t 1 2 3 -s 2", "-mx -ry 20"] {
            let f = PatternFrame::from_words(&w(words)).unwrap();
            for transform in [None, Some(&object)] {
                let mut sp = ShadingPoint::new(&ray, &hit, DVec3::new(5.0, -3.0, 1.0));
                sp.transform = transform;
                sp.uv = Some([0.25, 0.75]);
                let all = f.channels(&sp);
                for mask in [
                    0u32,
                    1 << 2 | 1 << 10,
                    0b111 << 6,
                    0xfff << 12,
                    1 << 3,
                    0x7ff_ffff,
                ] {
                    let some = f.channels_for(&sp, mask);
                    for c in 0..CHANNELS {
                        if mask & (1 << c) != 0 {
                            assert_eq!(some[c].to_bits(), all[c].to_bits(), "{words} {c}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn bad_transforms_are_refused() {
        let w = |s: &str| s.split_whitespace().map(String::from).collect::<Vec<_>>();
        assert!(PatternFrame::from_words(&w("-t 1 2")).is_err());
        assert!(PatternFrame::from_words(&w("-rz 90 junk")).is_err());
        assert_eq!(
            PatternFrame::from_words(&[]).unwrap(),
            PatternFrame::identity()
        );
    }

    #[test]
    fn texture_vectors_go_back_to_the_world() {
        let w: Vec<String> = "-rz 90 -s 2".split_whitespace().map(String::from).collect();
        let f = PatternFrame::from_words(&w).unwrap();
        let ray = Ray::primary(DVec3::Z, -DVec3::Z, f64::INFINITY);
        let hit = Hit {
            obj: 0,
            inst: crate::render::ray::NO_INST,
            t: 1.0,
            point: DVec3::ZERO,
            normal: DVec3::Z,
            back: false,
            flat: true,
            material: None,
            antimatter: [None; MAX_ANTIMATTER],
        };
        let sp = ShadingPoint::new(&ray, &hit, DVec3::ZERO);
        // A unit x in the pattern frame is the world's y, still unit length.
        let v = f.vector_to_world(&sp, DVec3::X);
        assert!((v - DVec3::Y).length() < 1e-12, "{v}");
    }
}
