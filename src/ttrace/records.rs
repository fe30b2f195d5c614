//! ttrace's records: rays read as rtrace reads them (origin and direction, text or binary
//! floats) and results written as rtrace writes them (`%e` and tabs, or binary floats).

use crate::options::rtrace::Format;
use anyhow::{bail, Result};
use glam::DVec3;
use std::io::{BufRead, Read};

/// One input ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InRay {
    /// Origin.
    pub org: DVec3,
    /// Direction as given (not normalised; zero: the flush record).
    pub dir: DVec3,
}

/// Reads rays one record at a time.
pub struct RayReader<R> {
    input: R,
    format: Format,
    /// Records read so far.
    pub records: u64,
    /// Text lines read so far.
    line: u64,
    buf: String,
}

/// The longest text line read (a record is six numbers).
const MAX_LINE: usize = 1 << 16;

impl<R: BufRead> RayReader<R> {
    /// A reader of `format` records.
    pub fn new(input: R, format: Format) -> Self {
        RayReader {
            input,
            format,
            records: 0,
            line: 0,
            buf: String::new(),
        }
    }

    /// The next ray, None at the end of the input; a bad record is an error naming it.
    pub fn next_ray(&mut self) -> Result<Option<InRay>> {
        match self.format {
            Format::Ascii => self.next_text(),
            Format::Float => self.next_binary(4),
            Format::Double => self.next_binary(8),
        }
    }

    fn next_text(&mut self) -> Result<Option<InRay>> {
        loop {
            self.buf.clear();
            let n = (&mut self.input)
                .take(MAX_LINE as u64 + 1)
                .read_line(&mut self.buf)?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            if self.buf.len() > MAX_LINE {
                bail!(
                    "standard input, line {}: longer than {MAX_LINE} bytes (a record is six numbers)",
                    self.line
                );
            }
            let words: Vec<&str> = self.buf.split_whitespace().collect();
            if words.is_empty() {
                continue;
            }
            let rec = self.records + 1;
            if words.len() != 6 {
                bail!(
                    "standard input, line {} (record {rec}): {} numbers, a record is six \
                     (origin x y z, direction x y z)",
                    self.line,
                    words.len()
                );
            }
            let mut v = [0f64; 6];
            for (k, w) in words.iter().enumerate() {
                let x: f64 = w
                    .parse()
                    .ok()
                    .filter(|x: &f64| x.is_finite())
                    .ok_or_else(|| {
                        let shown: String = w.chars().take(40).collect();
                        anyhow::anyhow!(
                            "standard input, line {} (record {rec}): '{}' is not a finite number",
                            self.line,
                            shown.escape_debug()
                        )
                    })?;
                v[k] = x;
            }
            self.records += 1;
            return Ok(Some(InRay {
                org: DVec3::new(v[0], v[1], v[2]),
                dir: DVec3::new(v[3], v[4], v[5]),
            }));
        }
    }

    fn next_binary(&mut self, size: usize) -> Result<Option<InRay>> {
        let mut b = [0u8; 48];
        let want = 6 * size;
        let mut got = 0;
        while got < want {
            let n = self.input.read(&mut b[got..want])?;
            if n == 0 {
                break;
            }
            got += n;
        }
        if got == 0 {
            return Ok(None);
        }
        let rec = self.records + 1;
        if got < want {
            bail!("standard input, record {rec}: {got} of its {want} bytes before the end");
        }
        let mut v = [0f64; 6];
        for (k, x) in v.iter_mut().enumerate() {
            *x = if size == 4 {
                f32::from_ne_bytes(b[4 * k..4 * k + 4].try_into().expect("4 bytes")) as f64
            } else {
                f64::from_ne_bytes(b[8 * k..8 * k + 8].try_into().expect("8 bytes"))
            };
            if !x.is_finite() {
                bail!(
                    "standard input, record {rec}: number {} is not finite",
                    k + 1
                );
            }
        }
        self.records += 1;
        Ok(Some(InRay {
            org: DVec3::new(v[0], v[1], v[2]),
            dir: DVec3::new(v[3], v[4], v[5]),
        }))
    }
}

/// C's `%e`: six decimals, an exponent of at least two digits.
pub fn fmt_e(v: f64) -> String {
    crate::options::defaults::fmt_e(v, 6)
}

/// Writes result fields in the output format.
pub struct FieldWriter {
    /// The bytes written so far.
    pub out: Vec<u8>,
    format: Format,
}

impl FieldWriter {
    /// An empty writer.
    pub fn new(format: Format) -> Self {
        FieldWriter {
            out: Vec::new(),
            format,
        }
    }

    /// A number.
    pub fn num(&mut self, v: f64) {
        let v = if v.is_finite() { v } else { 0.0 };
        match self.format {
            Format::Ascii => {
                self.out.extend_from_slice(fmt_e(v).as_bytes());
                self.out.push(b'\t');
            }
            Format::Float => self.out.extend_from_slice(&(v as f32).to_ne_bytes()),
            Format::Double => self.out.extend_from_slice(&v.to_ne_bytes()),
        }
    }

    /// Three numbers.
    pub fn vec3(&mut self, v: DVec3) {
        self.num(v.x);
        self.num(v.y);
        self.num(v.z);
    }

    /// A name (text output only, checked when the options are read).
    pub fn name(&mut self, s: &str) {
        self.out.extend_from_slice(s.as_bytes());
        self.out.push(b'\t');
    }

    /// The end of a record.
    pub fn end(&mut self) {
        if self.format == Format::Ascii {
            self.out.push(b'\n');
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_read_and_bad_ones_named() {
        let text = "0 0 1 0 0 -1\n\n1 2 3 4 5 6\n";
        let mut r = RayReader::new(text.as_bytes(), Format::Ascii);
        assert_eq!(
            r.next_ray().unwrap().unwrap().dir,
            DVec3::new(0.0, 0.0, -1.0)
        );
        assert_eq!(
            r.next_ray().unwrap().unwrap().org,
            DVec3::new(1.0, 2.0, 3.0)
        );
        assert!(r.next_ray().unwrap().is_none());
        for (bad, want) in [
            ("0 0 1 0 0\n", "line 1 (record 1): 5 numbers"),
            ("0 0 1 0 0 x\n", "'x' is not a finite number"),
            ("0 0 1 0 0 nan\n", "'nan' is not a finite number"),
        ] {
            let e = RayReader::new(bad.as_bytes(), Format::Ascii)
                .next_ray()
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{e}");
        }
        let mut b = Vec::new();
        for x in [1f32, 2.0, 3.0, 0.0, 0.0, 1.0] {
            b.extend_from_slice(&x.to_ne_bytes());
        }
        let mut r = RayReader::new(&b[..], Format::Float);
        assert_eq!(
            r.next_ray().unwrap().unwrap().org,
            DVec3::new(1.0, 2.0, 3.0)
        );
        let e = RayReader::new(&b[..10], Format::Float)
            .next_ray()
            .unwrap_err()
            .to_string();
        assert!(e.contains("record 1: 10 of its 24 bytes"), "{e}");
        assert_eq!(fmt_e(0.0), "0.000000e+00");
        assert_eq!(fmt_e(-1234.5), "-1.234500e+03");
        assert_eq!(fmt_e(1e-10), "1.000000e-10");
    }
}
