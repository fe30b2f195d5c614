//! Tokenizer for Radiance scene text.
//!
//! Scene text is a stream of whitespace-separated words. Newlines are free whitespace except
//! that they end `# comments` and `!command` lines. A word starting with `"` or `'` is quoted:
//! it runs to the matching quote on the same line and may contain spaces. A `!` where a
//! primitive may start begins an inline command that runs to the end of the line; a
//! backslash just before the newline continues it on the next line (the backslash-newline
//! pair is removed, as a shell would).

/// What a token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TokenKind {
    /// A word (possibly quoted; quotes removed).
    Word,
    /// An inline command (text after `!`, continuation lines joined, trimmed).
    Command,
}

/// One token with the line it starts on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Token {
    /// Word or command.
    pub kind: TokenKind,
    /// The text (quotes removed for quoted words).
    pub text: String,
    /// 1-based line where the token starts.
    pub line: u32,
    /// Whether the word was quoted.
    pub quoted: bool,
}

/// A lexical error: an unterminated quote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LexError {
    /// 1-based line of the problem.
    pub line: u32,
    /// What is wrong.
    pub reason: String,
}

/// Streaming tokenizer over scene text.
#[derive(Clone, Debug)]
pub struct Lexer<'a> {
    src: &'a str,
    pos: usize,
    line: u32,
}

impl<'a> Lexer<'a> {
    /// A lexer at the start of `src` (line 1).
    pub fn new(src: &'a str) -> Lexer<'a> {
        Lexer {
            src,
            pos: 0,
            line: 1,
        }
    }

    /// The current line (1-based).
    pub fn line(&self) -> u32 {
        self.line
    }

    fn peek(&self) -> Option<u8> {
        self.src.as_bytes().get(self.pos).copied()
    }

    /// Skip whitespace and `#` comments.
    fn skip_blank(&mut self) {
        while let Some(c) = self.peek() {
            if c == b'\n' {
                self.line += 1;
                self.pos += 1;
            } else if c.is_ascii_whitespace() {
                self.pos += 1;
            } else if c == b'#' {
                while let Some(c) = self.peek() {
                    if c == b'\n' {
                        break;
                    }
                    self.pos += 1;
                }
            } else {
                break;
            }
        }
    }

    /// The next token, or `None` at the end of the text. `commands` says whether a `!`
    /// starts an inline command here (true where a primitive may start).
    pub fn next_token(&mut self, commands: bool) -> Result<Option<Token>, LexError> {
        self.skip_blank();
        let Some(c) = self.peek() else {
            return Ok(None);
        };
        let line = self.line;
        if commands && c == b'!' {
            self.pos += 1;
            let mut text = String::new();
            loop {
                let rest = &self.src[self.pos..];
                let end = rest.find('\n').unwrap_or(rest.len());
                let piece = &rest[..end];
                let piece = piece.strip_suffix('\r').unwrap_or(piece);
                self.pos += end;
                if let Some(cont) = piece.strip_suffix('\\') {
                    text.push_str(cont);
                    if self.peek() == Some(b'\n') {
                        self.pos += 1;
                        self.line += 1;
                        continue;
                    }
                } else {
                    text.push_str(piece);
                }
                break;
            }
            return Ok(Some(Token {
                kind: TokenKind::Command,
                text: text.trim().to_string(),
                line,
                quoted: false,
            }));
        }
        if c == b'"' || c == b'\'' {
            self.pos += 1;
            let rest = &self.src[self.pos..];
            for (i, ch) in rest.char_indices() {
                if ch == '\n' {
                    break;
                }
                if ch as u32 == c as u32 {
                    let text = rest[..i].to_string();
                    self.pos += i + 1;
                    return Ok(Some(Token {
                        kind: TokenKind::Word,
                        text,
                        line,
                        quoted: true,
                    }));
                }
            }
            return Err(LexError {
                line,
                reason: format!("unterminated {} quote", c as char),
            });
        }
        let start = self.pos;
        while let Some(c) = self.peek() {
            if c.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
        // Whitespace is ASCII, so `pos` is always on a char boundary here.
        Ok(Some(Token {
            kind: TokenKind::Word,
            text: self.src[start..self.pos].to_string(),
            line,
            quoted: false,
        }))
    }
}

/// Characters that make a command line need a real shell when they appear unquoted.
const SHELL_META: &[char] = &[
    '|', '&', ';', '<', '>', '(', ')', '$', '`', '*', '?', '[', ']', '{', '}', '~', '\n',
];

/// Split a pipeline `cmd1 | cmd2 | ...` into its simple commands' words (see
/// [`split_command_words`]). `Ok(None)` when any part needs a real shell (including `||`
/// and an empty stage), `Err` for an unterminated quote.
pub fn split_pipeline(cmd: &str) -> Result<Option<Vec<Vec<String>>>, String> {
    let mut stages = Vec::new();
    let mut start = 0;
    let mut quote: Option<char> = None;
    let mut escaped = false;
    for (i, c) in cmd.char_indices() {
        if escaped {
            escaped = false;
            continue;
        }
        match (quote, c) {
            (Some('\''), '\'') => quote = None,
            (Some('\''), _) => {}
            (Some(_), '\\') => escaped = true,
            (Some(_), '"') => quote = None,
            (Some(_), _) => {}
            (None, '\\') => escaped = true,
            (None, '\'' | '"') => quote = Some(c),
            (None, '|') => {
                stages.push(&cmd[start..i]);
                start = i + 1;
            }
            (None, _) => {}
        }
    }
    stages.push(&cmd[start..]);
    let mut out = Vec::with_capacity(stages.len());
    for st in stages {
        match split_command_words(st)? {
            Some(w) if !w.is_empty() => out.push(w),
            _ => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// Split a command line into words like a POSIX shell would for a simple command
/// (single quotes literal, double quotes with `\"` `\\` `\$` `` \` `` escapes, backslash
/// escapes outside quotes). Returns `Ok(None)` when the line uses shell features (pipes,
/// redirections, variables, globs, assignments...) and so must go through a real shell, and
/// `Err` for an unterminated quote.
pub fn split_command_words(cmd: &str) -> Result<Option<Vec<String>>, String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut in_word = false;
    let mut chars = cmd.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(ch) => cur.push(ch),
                        None => return Err("unterminated ' quote in command".to_string()),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => match chars.peek() {
                            Some(&n) if matches!(n, '"' | '\\' | '$' | '`') => {
                                cur.push(n);
                                chars.next();
                            }
                            _ => cur.push('\\'),
                        },
                        Some('$') | Some('`') => return Ok(None),
                        Some(ch) => cur.push(ch),
                        None => return Err("unterminated \" quote in command".to_string()),
                    }
                }
            }
            '\\' => {
                in_word = true;
                match chars.next() {
                    Some(n) => cur.push(n),
                    None => return Ok(None),
                }
            }
            c if c.is_whitespace() => {
                if in_word {
                    words.push(std::mem::take(&mut cur));
                    in_word = false;
                }
            }
            c if SHELL_META.contains(&c) => return Ok(None),
            '#' if !in_word => return Ok(None),
            '=' if words.is_empty() => return Ok(None),
            c => {
                in_word = true;
                cur.push(c);
            }
        }
    }
    if in_word {
        words.push(cur);
    }
    Ok(Some(words))
}

/// Whether `w` is a Radiance real number: optional sign, digits with an optional point
/// (at least one digit), optional exponent.
pub fn is_real(w: &str) -> bool {
    let b = w.as_bytes();
    let mut i = 0;
    if matches!(b.first(), Some(b'+' | b'-')) {
        i += 1;
    }
    let mut digits = 0;
    while i < b.len() && b[i].is_ascii_digit() {
        i += 1;
        digits += 1;
    }
    if i < b.len() && b[i] == b'.' {
        i += 1;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
            digits += 1;
        }
    }
    if digits == 0 {
        return false;
    }
    if i < b.len() && matches!(b[i], b'e' | b'E') {
        i += 1;
        if matches!(b.get(i), Some(b'+' | b'-')) {
            i += 1;
        }
        let s = i;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i == s {
            return false;
        }
    }
    i == b.len()
}

/// Whether `w` is an integer (optional sign, digits).
pub fn is_int(w: &str) -> bool {
    let d = w.strip_prefix(['+', '-']).unwrap_or(w);
    !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(src: &str) -> Vec<Token> {
        let mut lx = Lexer::new(src);
        let mut v = Vec::new();
        while let Some(t) = lx.next_token(true).unwrap() {
            v.push(t);
        }
        v
    }

    #[test]
    fn words_quotes_comments_lines() {
        let t = all("a  'b c'\n# com ment\n\"d e\" f#g\n\n  h");
        let texts: Vec<_> = t
            .iter()
            .map(|t| (t.text.as_str(), t.line, t.quoted))
            .collect();
        assert_eq!(
            texts,
            vec![
                ("a", 1, false),
                ("b c", 1, true),
                ("d e", 3, true),
                ("f#g", 3, false),
                ("h", 5, false)
            ]
        );
    }

    #[test]
    fn command_with_continuation() {
        let t = all("!xform -t 1 2 3 \\\n  file.rad\nnext");
        assert_eq!(t[0].kind, TokenKind::Command);
        assert_eq!(t[0].text, "xform -t 1 2 3   file.rad");
        assert_eq!(t[0].line, 1);
        assert_eq!(t[1].text, "next");
        assert_eq!(t[1].line, 3);
    }

    #[test]
    fn bang_inside_args_is_a_word() {
        let mut lx = Lexer::new("!x");
        let t = lx.next_token(false).unwrap().unwrap();
        assert_eq!(t.kind, TokenKind::Word);
    }

    #[test]
    fn unterminated_quote() {
        let mut lx = Lexer::new("\n'abc\ndef'");
        let e = lx.next_token(true).unwrap_err();
        assert_eq!(e.line, 2);
    }

    #[test]
    fn split_commands() {
        assert_eq!(
            split_command_words("genbox m 'a b' 1 \"2\" 3").unwrap(),
            Some(
                vec!["genbox", "m", "a b", "1", "2", "3"]
                    .into_iter()
                    .map(String::from)
                    .collect()
            )
        );
        assert_eq!(
            split_command_words("genrev a | xform -rx 90").unwrap(),
            None
        );
        assert_eq!(split_command_words("xform $HOME/x").unwrap(), None);
        assert_eq!(split_command_words("A=1 xform x").unwrap(), None);
        assert_eq!(
            split_command_words("xform 'a|b'").unwrap(),
            Some(vec!["xform".to_string(), "a|b".to_string()])
        );
        assert!(split_command_words("xform 'a").is_err());
    }

    #[test]
    fn pipelines() {
        let p = split_pipeline("genrev a b 't|1' 2 | xform -rx 90")
            .unwrap()
            .unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0][3], "t|1");
        assert_eq!(p[1], vec!["xform", "-rx", "90"]);
        assert_eq!(split_pipeline("a || b").unwrap(), None);
        assert_eq!(split_pipeline("a | b > c").unwrap(), None);
        assert_eq!(split_pipeline("a |").unwrap(), None);
        assert_eq!(split_pipeline("a \\| b").unwrap().unwrap().len(), 1);
        assert!(split_pipeline("a 'b | c").is_err());
    }

    #[test]
    fn numbers() {
        for ok in [".5", "1e-3", "+2", "-1.", "3", "1E+10", "0.0"] {
            assert!(is_real(ok), "{ok}");
        }
        for bad in ["", ".", "e3", "1e", "nan", "inf", "1x", "--1", "+"] {
            assert!(!is_real(bad), "{bad}");
        }
        assert!(is_int("-3") && is_int("+0") && !is_int("1.0") && !is_int("-"));
    }
}
