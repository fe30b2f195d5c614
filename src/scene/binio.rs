//! Radiance's portable binary encoding (octrees `.oct` and compiled meshes `.rtm`): a text
//! header up to an empty line, then big-endian integers of 1–8 bytes (the first byte
//! sign-extended), NUL-terminated strings and 5-byte reals (a 4-byte mantissa and a 1-byte
//! exponent). Every read is checked against the end of the buffer; nothing is allocated
//! from a count in the file before the bytes it announces have been seen.

/// Largest header accepted (text lines before the binary part).
pub const MAX_HEADER: usize = 16 << 20;

/// A cursor over a file's bytes. Errors are one-line messages without the file name
/// (callers prefix it).
pub struct BinReader<'a> {
    buf: &'a [u8],
    pos: usize,
    kind: &'static str,
}

impl<'a> BinReader<'a> {
    /// A reader at the start of `buf`, a file of `kind` (`octree`, `mesh`: for messages).
    pub fn new(buf: &'a [u8], kind: &'static str) -> BinReader<'a> {
        BinReader { buf, pos: 0, kind }
    }

    /// The current byte offset.
    pub fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left.
    pub fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    fn truncated(&self, what: &str) -> String {
        format!(
            "truncated {} (reading {what} at byte {})",
            self.kind, self.pos
        )
    }

    /// An error about `what` at the current offset.
    pub fn bad(&self, what: impl std::fmt::Display) -> String {
        format!("{what} at byte {}", self.pos)
    }

    /// The next `n` bytes.
    pub fn bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if n > self.remaining() {
            return Err(self.truncated(what));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// One unsigned byte.
    pub fn byte(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.bytes(1, what)?[0])
    }

    /// A big-endian signed integer of `n` (1..=8) bytes.
    pub fn int(&mut self, n: usize, what: &str) -> Result<i64, String> {
        let b = self.bytes(n, what)?;
        let mut v: i64 = if b[0] & 0x80 != 0 { -1 } else { 0 };
        for &x in b {
            v = (v << 8) | x as i64;
        }
        Ok(v)
    }

    /// A big-endian unsigned integer of `n` (1..=8) bytes.
    pub fn uint(&mut self, n: usize, what: &str) -> Result<u64, String> {
        let b = self.bytes(n, what)?;
        Ok(b.iter().fold(0u64, |v, &x| (v << 8) | x as u64))
    }

    /// A non-negative count of `n` bytes, at most `max`.
    pub fn count(&mut self, n: usize, max: u64, what: &str) -> Result<usize, String> {
        let at = self.pos;
        let v = self.int(n, what)?;
        if v < 0 || v as u64 > max {
            return Err(format!("bad {what} {v} at byte {at}"));
        }
        Ok(v as usize)
    }

    /// A NUL-terminated string (UTF-8).
    pub fn string(&mut self, what: &str) -> Result<&'a str, String> {
        let rest = &self.buf[self.pos..];
        let Some(end) = rest.iter().position(|&b| b == 0) else {
            return Err(self.truncated(what));
        };
        let s = std::str::from_utf8(&rest[..end])
            .map_err(|_| self.bad(format!("{what}: not UTF-8")))?;
        self.pos += end + 1;
        Ok(s)
    }

    /// A real: a 4-byte mantissa m and a 1-byte exponent e, m = 0 meaning 0, otherwise
    /// (m + 0.5 − [m < 0]) / 2147483647 · 2^e.
    pub fn real(&mut self, what: &str) -> Result<f64, String> {
        let m = self.int(4, what)?;
        let e = self.int(1, what)?;
        if m == 0 {
            return Ok(0.0);
        }
        let f = (m as f64 + if m < 0 { -0.5 } else { 0.5 }) / 2147483647.0;
        Ok(f * 2f64.powi(e as i32))
    }

    /// A real written as text (`%.12g`, NUL-terminated): the octree cube.
    pub fn text_real(&mut self, what: &str) -> Result<f64, String> {
        let at = self.pos;
        let s = self.string(what)?;
        match s.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("bad {what} '{s}' at byte {at}")),
        }
    }

    /// The text header: lines up to an empty one, `#?RADIANCE` first (older writers, such
    /// as oconv before 1991, start with their command line instead: Radiance reads those
    /// too, and so does this). Returns the lines (without `#?RADIANCE`) and checks a
    /// `FORMAT=` line, when there is one, against `format`. Without `#?RADIANCE`, every
    /// header line must be text; what follows the header (a magic number) tells the rest.
    pub fn header(&mut self, format: &str) -> Result<Vec<String>, String> {
        let kind = self.kind;
        const MAGIC: &[u8] = b"#?RADIANCE\n";
        let marked = self.buf.starts_with(MAGIC);
        self.pos = if marked { MAGIC.len() } else { 0 };
        let mut lines = Vec::new();
        loop {
            let rest = &self.buf[self.pos..];
            let Some(end) = rest.iter().take(MAX_HEADER).position(|&b| b == b'\n') else {
                return Err(if rest.len() > MAX_HEADER {
                    format!("not a Radiance {kind} (header longer than {MAX_HEADER} bytes)")
                } else {
                    self.truncated("the header")
                });
            };
            let raw = &rest[..end];
            if !marked && raw.iter().any(|&b| b < b' ' && b != b'\t' && b != b'\r') {
                return Err(format!("not a Radiance {kind} (no #?RADIANCE header)"));
            }
            let line = String::from_utf8_lossy(raw).into_owned();
            self.pos += end + 1;
            if self.pos > MAX_HEADER {
                return Err(format!(
                    "not a Radiance {kind} (header longer than {MAX_HEADER} bytes)"
                ));
            }
            if line.is_empty() {
                break;
            }
            if let Some(f) = line.strip_prefix("FORMAT=") {
                if f.trim() != format {
                    return Err(format!("not a Radiance {kind} (FORMAT={})", f.trim()));
                }
            }
            lines.push(line);
        }
        Ok(lines)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_verified_encodings() {
        let cases: [(&[u8], f64); 4] = [
            (&[0x59, 0x99, 0x99, 0x98, 0x00], 0.7),
            (&[0x66, 0x66, 0x66, 0x65, 0xfd], 0.1),
            (&[0x3f, 0xff, 0xff, 0xff, 0x01], 1.0),
            (&[0, 0, 0, 0, 0], 0.0),
        ];
        for (b, want) in cases {
            let v = BinReader::new(b, "octree").real("r").unwrap();
            assert!((v - want).abs() < 1e-8, "{v} vs {want}");
        }
        let mut r = BinReader::new(&[0xff, 0xff, 0x01, 0x1f], "octree");
        assert_eq!(r.int(2, "i").unwrap(), -1);
        assert_eq!(r.int(2, "i").unwrap(), 287);
        assert!(r.int(1, "i").unwrap_err().contains("truncated"));
    }

    #[test]
    fn headers() {
        let mut r = BinReader::new(
            b"#?RADIANCE\noconv x\nFORMAT=Radiance_octree\n\n\x01",
            "octree",
        );
        assert_eq!(r.header("Radiance_octree").unwrap().len(), 2);
        assert_eq!(r.byte("b").unwrap(), 1);
        let mut r = BinReader::new(b"#?RADIANCE\nFORMAT=Radiance_tmesh\n\n", "octree");
        assert!(r.header("Radiance_octree").unwrap_err().contains("FORMAT"));
        assert!(BinReader::new(b"hello", "octree").header("x").is_err());
        assert!(BinReader::new(b"#?RADIANCE\nno end", "octree")
            .header("x")
            .is_err());
    }
}
