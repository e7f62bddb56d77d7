//! The tokenizer: pbrt-v4's token rules (parser.cpp, `Tokenizer::Next`) with
//! a file, line and column on every token.
//!
//! Tokens are separated by spaces, tabs, CR and LF. `[` and `]` are tokens by
//! themselves; `"` starts a string that must end on the same line (escapes
//! `\b \f \n \r \t \\ \' \"`); `#` starts a comment to the end of the line;
//! anything else runs to the next separator, quote or bracket and is a number
//! when it reads as one (decimal, optional sign, fraction and exponent, finite),
//! else a word (a directive, `true`, `false`, or a malformed number the parser
//! reports where it expected a number).

use super::error::{Loc, PbrtError, Result};
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum TokenKind {
    Open,
    Close,
    /// A quoted string, without its quotes, escapes decoded.
    Str(String),
    /// A number; `int` is its value when it is written as an integer
    /// (digits with an optional sign) that fits in 64 bits.
    Num {
        value: f64,
        int: Option<i64>,
    },
    /// Anything else: directives, `true`/`false`, and malformed numbers.
    Word(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    pub kind: TokenKind,
    pub loc: Loc,
}

impl Token {
    /// The token as the file wrote it (strings re-quoted), for messages.
    pub fn describe(&self) -> String {
        match &self.kind {
            TokenKind::Open => "'['".into(),
            TokenKind::Close => "']'".into(),
            TokenKind::Str(s) => format!("\"{}\"", s.escape_debug()),
            TokenKind::Num { value, int } => match int {
                Some(i) => format!("'{i}'"),
                // Large and tiny numbers as the file most likely wrote them.
                None if value.abs() >= 1e16 || (*value != 0.0 && value.abs() < 1e-6) => format!("'{value:e}'"),
                None => format!("'{value}'"),
            },
            TokenKind::Word(w) => format!("'{}'", w.escape_debug()),
        }
    }
}

/// Reads one file's text into tokens.
pub struct Lexer {
    text: Vec<u8>,
    pos: usize,
    line: u32,
    col: u32,
    file: Arc<PathBuf>,
}

impl Lexer {
    /// A lexer over a file's bytes. Text that is not UTF-8 is an error at the
    /// first bad byte; UTF-16 (pbrt-v4 refuses it too) is named as such.
    pub fn new(file: Arc<PathBuf>, bytes: Vec<u8>) -> Result<Lexer> {
        if bytes.len() >= 2 && (bytes[..2] == [0xfe, 0xff] || bytes[..2] == [0xff, 0xfe]) {
            return Err(PbrtError::at(
                &Loc::new(file, 1, 1),
                "the file is UTF-16 text; pbrt scene files are UTF-8",
            ));
        }
        if let Err(e) = std::str::from_utf8(&bytes) {
            let good = e.valid_up_to();
            let mut line = 1u32;
            let mut col = 1u32;
            for &b in &bytes[..good] {
                if b == b'\n' {
                    line = line.saturating_add(1);
                    col = 1;
                } else if b & 0xc0 != 0x80 {
                    col = col.saturating_add(1);
                }
            }
            return Err(PbrtError::at(&Loc::new(file, line, col), "the file is not UTF-8 text"));
        }
        // A UTF-8 byte order mark is not a token.
        let pos = if bytes.starts_with(&[0xef, 0xbb, 0xbf]) { 3 } else { 0 };
        Ok(Lexer {
            text: bytes,
            pos,
            line: 1,
            col: 1,
            file,
        })
    }

    pub fn file(&self) -> &Arc<PathBuf> {
        &self.file
    }

    fn loc(&self) -> Loc {
        Loc::new(self.file.clone(), self.line, self.col)
    }

    fn peek(&self) -> Option<u8> {
        self.text.get(self.pos).copied()
    }

    fn bump(&mut self) -> Option<u8> {
        let b = self.peek()?;
        self.pos += 1;
        if b == b'\n' {
            self.line = self.line.saturating_add(1);
            self.col = 1;
        } else if b & 0xc0 != 0x80 {
            // Count characters: UTF-8 continuation bytes add no column.
            self.col = self.col.saturating_add(1);
        }
        Some(b)
    }

    /// The next token, or None at the end of the file.
    pub fn next_token(&mut self) -> Result<Option<Token>> {
        loop {
            let loc = self.loc();
            let Some(b) = self.bump() else {
                return Ok(None);
            };
            match b {
                b' ' | b'\n' | b'\t' | b'\r' => {}
                b'#' => {
                    while let Some(c) = self.peek() {
                        if c == b'\n' || c == b'\r' {
                            break;
                        }
                        self.bump();
                    }
                }
                b'[' => {
                    return Ok(Some(Token {
                        kind: TokenKind::Open,
                        loc,
                    }))
                }
                b']' => {
                    return Ok(Some(Token {
                        kind: TokenKind::Close,
                        loc,
                    }))
                }
                b'"' => return self.string(loc).map(Some),
                _ => {
                    let start = self.pos - 1;
                    while let Some(c) = self.peek() {
                        if matches!(c, b' ' | b'\n' | b'\t' | b'\r' | b'"' | b'[' | b']') {
                            break;
                        }
                        self.bump();
                    }
                    // Valid UTF-8 split at ASCII delimiters stays valid.
                    let word = String::from_utf8_lossy(&self.text[start..self.pos]).into_owned();
                    return Ok(Some(Token {
                        kind: classify(word),
                        loc,
                    }));
                }
            }
        }
    }

    fn string(&mut self, loc: Loc) -> Result<Token> {
        let mut bytes = Vec::new();
        loop {
            let Some(b) = self.bump() else {
                return Err(PbrtError::at(&loc, "unterminated string: the file ends inside it"));
            };
            match b {
                b'"' => break,
                b'\n' | b'\r' => {
                    return Err(PbrtError::at(
                        &loc,
                        "unterminated string: a string must end on the line it starts",
                    ))
                }
                b'\\' => {
                    let at = self.loc();
                    let decoded = match self.bump() {
                        None => return Err(PbrtError::at(&loc, "unterminated string: the file ends inside it")),
                        Some(b'b') => 0x08,
                        Some(b'f') => 0x0c,
                        Some(b'n') => b'\n',
                        Some(b'r') => b'\r',
                        Some(b't') => b'\t',
                        Some(b'\\') => b'\\',
                        Some(b'\'') => b'\'',
                        Some(b'"') => b'"',
                        Some(c) => {
                            let shown = if c.is_ascii_graphic() {
                                (c as char).to_string()
                            } else {
                                format!("byte 0x{c:02x}")
                            };
                            return Err(PbrtError::at(&at, format!("unknown escape '\\{shown}' in a string")));
                        }
                    };
                    bytes.push(decoded);
                }
                _ => bytes.push(b),
            }
        }
        Ok(Token {
            kind: TokenKind::Str(String::from_utf8_lossy(&bytes).into_owned()),
            loc,
        })
    }
}

/// A number if the word reads as a finite decimal number, else a word.
fn classify(word: String) -> TokenKind {
    let b = word.as_bytes();
    let numeric_start = b
        .first()
        .is_some_and(|c| c.is_ascii_digit() || matches!(c, b'+' | b'-' | b'.'));
    let numeric_chars = b
        .iter()
        .all(|c| c.is_ascii_digit() || matches!(c, b'+' | b'-' | b'.' | b'e' | b'E'));
    if numeric_start && numeric_chars {
        if let Ok(value) = word.parse::<f64>() {
            if value.is_finite() {
                let digits = b.strip_prefix(b"-").or_else(|| b.strip_prefix(b"+")).unwrap_or(b);
                let int = if !digits.is_empty() && digits.iter().all(u8::is_ascii_digit) {
                    word.parse::<i64>().ok()
                } else {
                    None
                };
                return TokenKind::Num { value, int };
            }
        }
    }
    TokenKind::Word(word)
}
