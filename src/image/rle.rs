//! RGBE pixels and the scanline codec of Radiance pictures (the format is described in
//! `hdr.rs`): new run-length encoding (four component streams of run and literal packets),
//! old run-length encoding (`1 1 1 n` repeats) and flat scanlines.

use std::io::{self, BufRead};

/// Scanlines shorter than this are written flat (Radiance's `MINELEN`, 17 since 2024).
pub(super) const MIN_RLE_WIDTH: usize = 17;
/// Scanlines longer than this are written flat (the length must fit in 15 bits).
pub(super) const MAX_RLE_WIDTH: usize = 0x7fff;
/// Shortest run worth a run packet.
const MIN_RUN: usize = 4;
/// Longest run packet (count byte 255).
const MAX_RUN: usize = 127;
/// Longest literal packet.
const MAX_LITERAL: usize = 128;
/// Encode a linear RGB colour as RGBE, exactly as Radiance's `setcolr`: `d = max(r,g,b)`; if
/// `d <= 1e-32` the pixel is `0 0 0 0`; otherwise with `d = m * 2^e` (`0.5 <= m < 1`) each
/// mantissa byte is `trunc(c * 256 / 2^e)` and the exponent byte `e + 128`.
///
/// Negative, NaN and infinite components count as 0. Colours too bright for RGBE (above
/// about 1.7e38) saturate to `ff ff ff ff`.
#[inline]
pub fn float_to_rgbe(c: [f32; 3]) -> [u8; 4] {
    #[inline(always)]
    fn clean(v: f32) -> f32 {
        // NaN compares false, so it becomes 0 too.
        if v > 0.0 && v < f32::INFINITY {
            v
        } else {
            0.0
        }
    }
    let (r, g, b) = (clean(c[0]), clean(c[1]), clean(c[2]));
    let d = r.max(g).max(b);
    if d <= RGBE_ZERO {
        return [0; 4];
    }
    // d is a normal f32 here (> 1e-32), so its binary exponent gives frexp's e directly.
    let e = ((d.to_bits() >> 23) & 0xff) as i32 - 126;
    if e > 127 {
        return [255; 4];
    }
    // Multiplying by 256 / 2^e (a power of two, normal for every e here) is exact, so this
    // truncates exactly what Radiance's double arithmetic truncates.
    let scale = f32::from_bits(((8 - e + 127) as u32) << 23);
    [
        (r * scale) as u8,
        (g * scale) as u8,
        (b * scale) as u8,
        (e + 128) as u8,
    ]
}

/// The largest f32 that is `<= 1e-32` as a double: Radiance writes black at or below 1e-32.
const RGBE_ZERO: f32 = f32::from_bits(1e-32f32.to_bits() - 1);

/// Decode an RGBE pixel as Radiance does: `(m + 0.5) * 2^(E - 136)` per component, black when
/// the exponent byte `E` is 0.
#[inline]
pub fn rgbe_to_float(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let f = pow2(p[3] as i32 - 136);
    [
        ((p[0] as f64 + 0.5) * f) as f32,
        ((p[1] as f64 + 0.5) * f) as f32,
        ((p[2] as f64 + 0.5) * f) as f32,
    ]
}

/// `2^k` as an exact f64, for `-1022 <= k <= 1023`.
#[inline]
fn pow2(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// Append one component stream of a new-RLE scanline to `out`.
///
/// Radiance walks the line in groups of equal bytes and turns the first group of 4 or more into a
/// run; that group always starts at the first position where 4 equal bytes begin, which is what
/// `next_run` finds in one pass.
fn encode_stream(src: &[u8], out: &mut Vec<u8>) {
    let n = src.len();
    let mut j = 0; // first byte not yet written
    while j < n {
        let (beg, run) = next_run(src, j);
        // Bytes before the run: 2 or 3 equal bytes become a short run, the rest literals.
        let lit = &src[j..beg];
        if (2..MIN_RUN).contains(&lit.len()) && lit.iter().all(|&b| b == lit[0]) {
            out.push(128 + lit.len() as u8);
            out.push(lit[0]);
        } else {
            for chunk in lit.chunks(MAX_LITERAL) {
                out.push(chunk.len() as u8);
                out.extend_from_slice(chunk);
            }
        }
        if run > 0 {
            out.push(128 + run as u8);
            out.push(src[beg]);
            j = beg + run;
        } else {
            j = n;
        }
    }
}

/// The first run of at least `MIN_RUN` equal bytes at or after `j`: its start and its length
/// (capped at `MAX_RUN`), or `(src.len(), 0)` when there is none.
#[inline]
fn next_run(src: &[u8], j: usize) -> (usize, usize) {
    let n = src.len();
    let mut i = j;
    while i + MIN_RUN <= n {
        let b = src[i];
        if src[i + 1] != b {
            i += 1;
        } else if src[i + 2] != b {
            i += 2;
        } else if src[i + 3] != b {
            i += 3;
        } else {
            let mut run = MIN_RUN;
            while run < MAX_RUN && i + run < n && src[i + run] == b {
                run += 1;
            }
            return (i, run);
        }
    }
    (n, 0)
}

/// Append one encoded row of pixels to `out`. `comp` is scratch space.
pub(super) fn encode_row(row: &[[f32; 3]], out: &mut Vec<u8>, comp: &mut [Vec<u8>; 4]) {
    let w = row.len();
    if !(MIN_RLE_WIDTH..=MAX_RLE_WIDTH).contains(&w) {
        out.reserve(4 * w);
        for &c in row {
            out.extend_from_slice(&float_to_rgbe(c));
        }
        return;
    }
    for v in comp.iter_mut() {
        v.clear();
    }
    let [cr, cg, cb, ce] = comp;
    for &c in row {
        let p = float_to_rgbe(c);
        cr.push(p[0]);
        cg.push(p[1]);
        cb.push(p[2]);
        ce.push(p[3]);
    }
    out.reserve(4 + 4 * w + 4 * (w / 128 + 1));
    out.extend_from_slice(&[2, 2, (w >> 8) as u8, (w & 0xff) as u8]);
    for v in comp.iter() {
        encode_stream(v, out);
    }
}

/// Read one byte.
#[inline]
fn byte<R: BufRead>(r: &mut R) -> io::Result<u8> {
    let b = match r.fill_buf()?.first() {
        Some(&b) => b,
        None => return Err(io::ErrorKind::UnexpectedEof.into()),
    };
    r.consume(1);
    Ok(b)
}

/// Read one scanline of `w` pixels in whatever encoding it uses and append it to `out`.
/// `Ok(Err(reason))` for corrupt data. Flat lines grow `out` as their data arrives, so a bogus
/// width in a short file costs no huge allocation.
pub(super) fn read_scanline<R: BufRead>(
    r: &mut R,
    w: usize,
    out: &mut Vec<[u8; 4]>,
    comp: &mut Vec<u8>,
) -> io::Result<Result<(), String>> {
    let mut first = [0u8; 4];
    r.read_exact(&mut first)?;
    if (8..=MAX_RLE_WIDTH).contains(&w) && first[0] == 2 && first[1] == 2 && first[2] & 0x80 == 0 {
        // New RLE.
        let len = (first[2] as usize) << 8 | first[3] as usize;
        if len != w {
            return Ok(Err(format!(
                "run-length scanline says {len} pixels, the picture is {w} wide"
            )));
        }
        comp.resize(w, 0);
        let start = out.len();
        out.resize(start + w, [0; 4]);
        for i in 0..4 {
            let mut j = 0;
            while j < w {
                let code = byte(r)? as usize;
                if code > 128 {
                    let n = code - 128;
                    if j + n > w {
                        return Ok(Err("run overruns the scanline".into()));
                    }
                    let v = byte(r)?;
                    comp[j..j + n].fill(v);
                    j += n;
                } else if code == 0 {
                    return Ok(Err("zero-length packet".into()));
                } else if j + code > w {
                    return Ok(Err("literal overruns the scanline".into()));
                } else {
                    r.read_exact(&mut comp[j..j + code])?;
                    j += code;
                }
            }
            for (p, &v) in out[start..].iter_mut().zip(comp.iter()) {
                p[i] = v;
            }
        }
        return Ok(Ok(()));
    }
    // Flat pixels, possibly with old-style repeat pixels (1 1 1 n): n << shift copies of the
    // previous pixel, the shift growing by 8 for each consecutive repeat pixel.
    let end = out.len() + w;
    let start = out.len();
    let mut shift = 0u32;
    let mut px = first;
    loop {
        if px[0] == 1 && px[1] == 1 && px[2] == 1 {
            if out.len() == start {
                return Ok(Err("repeat code at the start of a scanline".into()));
            }
            if shift > 24 {
                return Ok(Err("repeat count too large".into()));
            }
            let n = (px[3] as usize) << shift;
            if out.len() + n > end {
                return Ok(Err("repeat count overruns the scanline".into()));
            }
            let prev = out[out.len() - 1];
            out.extend(std::iter::repeat_n(prev, n));
            shift += 8;
        } else {
            out.push(px);
            shift = 0;
        }
        if out.len() >= end {
            return Ok(Ok(()));
        }
        r.read_exact(&mut px)?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgbe_known_values() {
        let c = rgbe_to_float([0xff, 0xfe, 0xfe, 0x7e]);
        assert!(
            (c[0] - 0.24951).abs() < 1e-5
                && (c[1] - 0.24854).abs() < 1e-5
                && (c[2] - 0.24854).abs() < 1e-5,
            "{c:?}"
        );
        assert_eq!(float_to_rgbe(c), [0xff, 0xfe, 0xfe, 0x7e]);
        assert_eq!(float_to_rgbe([1.0, 0.0, 0.0]), [128, 0, 0, 129]);
        assert_eq!(float_to_rgbe([0.5, 0.5, 0.5]), [128, 128, 128, 128]);
        assert_eq!(float_to_rgbe([0.0; 3]), [0; 4]);
        assert_eq!(float_to_rgbe([1e-33, 0.0, 0.0]), [0; 4]);
        assert_eq!(rgbe_to_float([0; 4]), [0.0; 3]);
        assert_eq!(rgbe_to_float([12, 34, 56, 0]), [0.0; 3]);
        // Truncation, not rounding: 0.999 * 256 = 255.7 -> 255 at exponent 0 (+128).
        assert_eq!(float_to_rgbe([0.999, 0.0, 0.0]), [255, 0, 0, 128]);
    }

    #[test]
    fn rgbe_cleans_bad_input() {
        assert_eq!(float_to_rgbe([f32::NAN, f32::INFINITY, -1.0]), [0; 4]);
        assert_eq!(
            float_to_rgbe([f32::NAN, 1.0, f32::NEG_INFINITY]),
            [0, 128, 0, 129]
        );
        assert_eq!(float_to_rgbe([f32::MAX, 0.0, 0.0]), [255; 4]);
        let big = rgbe_to_float(float_to_rgbe([1e38, 1e38, 1e38]));
        assert!((big[0] / 1e38 - 1.0).abs() < 0.01);
    }

    #[test]
    fn rgbe_round_trip_precision() {
        let mut x = 1e-30f32;
        while x < 1e37 {
            let c = [x, x * 0.37, x * 0.001];
            let d = rgbe_to_float(float_to_rgbe(c));
            for i in 0..3 {
                // error at most one mantissa step of the largest component
                assert!((d[i] - c[i]).abs() <= x / 128.0, "{c:?} -> {d:?}");
            }
            x *= 1.7;
        }
    }

    #[test]
    fn stream_encoding_matches_radiance() {
        let enc = |s: &[u8]| {
            let mut o = Vec::new();
            encode_stream(s, &mut o);
            o
        };
        // The 48-wide exponent stream from the facts: literal 1, run 46, literal 1.
        let mut e = vec![0x7e];
        e.extend(std::iter::repeat_n(0x7f, 46));
        e.push(0x7e);
        assert_eq!(enc(&e), [0x01, 0x7e, 0xae, 0x7f, 0x01, 0x7e]);
        // Short runs of 2-3 before a long run / at the end.
        assert_eq!(enc(&[5, 5, 7, 7, 7, 7]), [0x82, 5, 0x84, 7]);
        assert_eq!(enc(&[1, 2, 3, 3, 3]), [0x05, 1, 2, 3, 3, 3]); // only a whole pending stretch becomes a short run
        assert_eq!(enc(&[1, 2, 3, 3, 3, 3]), [0x02, 1, 2, 0x84, 3]);
        assert_eq!(enc(&[9, 9, 9]), [0x83, 9]);
        assert_eq!(enc(&[1, 2, 3]), [0x03, 1, 2, 3]);
        // Runs are capped at 127 and literals at 128.
        let long = vec![4u8; 300];
        assert_eq!(enc(&long), [0xff, 4, 0xff, 4, 0x80 + 46, 4]);
        let lit: Vec<u8> = (0..200).map(|i| (i % 2) as u8).collect();
        let o = enc(&lit);
        assert_eq!(o[0], 128);
        assert_eq!(o[129], 72);
        assert_eq!(o.len(), 202);
    }
}
