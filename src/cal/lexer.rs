//! The tokens of the function language (Radiance's calexpr.c lexical rules, §1.2 of the
//! format reference): nested `{}` comments, names with backquote context marks, unsigned
//! numbers, `$N` channels and the one-character operators.

/// Identifiers keep at most this many bytes; the rest of a longer name is skipped.
pub(crate) const MAX_NAME: usize = 127;

/// One token.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Tok {
    /// An unsigned number.
    Num(f64),
    /// An identifier (possibly with backquotes).
    Name(String),
    /// `$` followed by digits (saturated at u32::MAX).
    Chan(u32),
    /// Any other character: `+ - * / ^ ( ) , ; = :` and the characters the grammar
    /// rejects (`<`, `%`, …), which the parser reports where they appear.
    Char(u8),
    /// End of the text.
    Eof,
}

/// A lexical error and where it was found.
#[derive(Debug, Clone)]
pub(crate) struct LexError {
    pub line: u32,
    pub col: u32,
    pub message: &'static str,
}

/// A scanner over the bytes of a text, tracking 1-based line and column.
pub(crate) struct Lexer<'a> {
    src: &'a [u8],
    pos: usize,
    line: u32,
    col: u32,
}

fn is_name_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'`'
}

fn is_name_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || c == b'`'
}

impl<'a> Lexer<'a> {
    pub fn new(src: &'a [u8]) -> Lexer<'a> {
        Lexer {
            src,
            pos: 0,
            line: 1,
            col: 1,
        }
    }

    fn peek(&self) -> Option<u8> {
        self.src.get(self.pos).copied()
    }

    fn bump(&mut self) {
        if let Some(c) = self.peek() {
            self.pos += 1;
            if c == b'\n' {
                self.line += 1;
                self.col = 1;
            } else {
                self.col += 1;
            }
        }
    }

    fn err(&self, message: &'static str) -> LexError {
        LexError {
            line: self.line,
            col: self.col,
            message,
        }
    }

    /// Skip whitespace and (nested) comments.
    fn skip_blank(&mut self) -> Result<(), LexError> {
        loop {
            match self.peek() {
                Some(c) if c.is_ascii_whitespace() || c == 0x0b => self.bump(),
                Some(b'{') => {
                    let mut depth = 0usize;
                    loop {
                        match self.peek() {
                            None => return Err(self.err("'}' expected")),
                            Some(b'{') => depth += 1,
                            Some(b'}') => depth -= 1,
                            _ => {}
                        }
                        self.bump();
                        if depth == 0 {
                            break;
                        }
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    /// The next token and the line and column where it starts.
    pub fn next(&mut self) -> Result<(Tok, u32, u32), LexError> {
        self.skip_blank()?;
        let (line, col) = (self.line, self.col);
        let Some(c) = self.peek() else {
            return Ok((Tok::Eof, line, col));
        };
        let tok = if c.is_ascii_digit() || c == b'.' {
            Tok::Num(self.number()?)
        } else if is_name_start(c) {
            Tok::Name(self.name())
        } else if c == b'$' && self.src.get(self.pos + 1).is_some_and(u8::is_ascii_digit) {
            self.bump();
            let mut n: u32 = 0;
            while let Some(d) = self.peek().filter(u8::is_ascii_digit) {
                n = n.saturating_mul(10).saturating_add((d - b'0') as u32);
                self.bump();
            }
            Tok::Chan(n)
        } else {
            self.bump();
            Tok::Char(c)
        };
        Ok((tok, line, col))
    }

    fn name(&mut self) -> String {
        let start = self.pos;
        while self.peek().is_some_and(is_name_char) {
            self.bump();
        }
        let end = self.pos.min(start + MAX_NAME);
        // Only ASCII bytes can be in a name.
        String::from_utf8_lossy(&self.src[start..end]).into_owned()
    }

    fn digits(&mut self) -> usize {
        let mut n = 0;
        while self.peek().is_some_and(|c| c.is_ascii_digit()) {
            self.bump();
            n += 1;
        }
        n
    }

    fn number(&mut self) -> Result<f64, LexError> {
        let start = self.pos;
        let mut nd = self.digits();
        if self.peek() == Some(b'.') {
            self.bump();
            nd += self.digits();
        }
        if nd == 0 {
            return Err(self.err("badly formed number"));
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            self.bump();
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.bump();
            }
            if self.digits() == 0 {
                return Err(self.err("missing exponent"));
            }
        }
        let text = std::str::from_utf8(&self.src[start..self.pos]).unwrap_or("0");
        // Normalise "5." and "5.e3" to forms every f64 parser takes.
        let mut s = String::with_capacity(text.len() + 2);
        if text.starts_with('.') {
            s.push('0');
        }
        let b = text.as_bytes();
        for (i, ch) in text.chars().enumerate() {
            s.push(ch);
            if ch == '.' && !b.get(i + 1).is_some_and(u8::is_ascii_digit) {
                s.push('0');
            }
        }
        Ok(s.parse::<f64>().unwrap_or(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Result<Vec<Tok>, &'static str> {
        let mut lx = Lexer::new(s.as_bytes());
        let mut v = Vec::new();
        loop {
            match lx.next() {
                Ok((Tok::Eof, _, _)) => return Ok(v),
                Ok((t, _, _)) => v.push(t),
                Err(e) => return Err(e.message),
            }
        }
    }

    #[test]
    fn numbers() {
        assert_eq!(
            toks("5. .5e1 1e-3 2E+2"),
            Ok(vec![
                Tok::Num(5.0),
                Tok::Num(5.0),
                Tok::Num(1e-3),
                Tok::Num(200.0)
            ])
        );
        assert_eq!(toks("."), Err("badly formed number"));
        assert_eq!(toks("1.e"), Err("missing exponent"));
        assert_eq!(toks("1e+x"), Err("missing exponent"));
    }

    #[test]
    fn comments_nest() {
        assert_eq!(toks("3{c {n} s}+4").unwrap().len(), 3);
        assert_eq!(toks("3 {open {x}"), Err("'}' expected"));
    }

    #[test]
    fn names_and_channels() {
        assert_eq!(
            toks("a.b un2`P. $12 $ %"),
            Ok(vec![
                Tok::Name("a.b".into()),
                Tok::Name("un2`P.".into()),
                Tok::Chan(12),
                Tok::Char(b'$'),
                Tok::Char(b'%')
            ])
        );
        let long = "x".repeat(200);
        assert_eq!(toks(&long), Ok(vec![Tok::Name("x".repeat(MAX_NAME))]));
    }
}
