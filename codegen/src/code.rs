//! Shared writer helpers: an indented line buffer and a `Namer` that makes the model's
//! name a legal, non-reserved identifier prefix.

use core::fmt::Write as _;

/// Lines of code with a current indent level (4 spaces per level).
#[derive(Debug, Default)]
pub struct Code {
    out: String,
    level: usize,
}

impl Code {
    pub fn new() -> Self {
        Code::default()
    }

    /// One line at the current level (empty lines get no trailing spaces).
    pub fn line(&mut self, s: impl AsRef<str>) {
        let s = s.as_ref();
        if !s.is_empty() {
            for _ in 0..self.level {
                self.out.push_str("    ");
            }
            self.out.push_str(s);
        }
        self.out.push('\n');
    }

    /// A line that opens a block (`... {`), then one level deeper.
    pub fn open(&mut self, s: impl AsRef<str>) {
        self.line(s);
        self.level += 1;
    }

    /// One level back, then a closing line (`}` or `} else {`).
    pub fn close(&mut self, s: impl AsRef<str>) {
        self.level = self.level.saturating_sub(1);
        self.line(s);
    }

    /// `} else {` at the block's level.
    pub fn reopen(&mut self, s: impl AsRef<str>) {
        self.level = self.level.saturating_sub(1);
        self.line(s);
        self.level += 1;
    }

    pub fn blank(&mut self) {
        self.out.push('\n');
    }

    /// Values wrapped at about 100 columns, comma separated, at the current level + 1.
    pub fn list(&mut self, items: &[String]) {
        let mut row = String::new();
        let n = items.len();
        for (i, it) in items.iter().enumerate() {
            let sep = if i + 1 < n { "," } else { "" };
            if !row.is_empty() && row.len() + it.len() + 2 > 96 {
                self.line(format!("    {}", row.trim_end()));
                row.clear();
            }
            let _ = write!(row, "{it}{sep} ");
        }
        if !row.is_empty() {
            self.line(format!("    {}", row.trim_end()));
        }
    }

    pub fn finish(self) -> String {
        self.out
    }
}

/// Makes identifiers legal and keeps them off a language's reserved words.
#[derive(Debug)]
pub struct Namer {
    reserved: &'static [&'static str],
}

impl Namer {
    pub fn new(reserved: &'static [&'static str]) -> Self {
        Namer { reserved }
    }

    /// `raw` as an identifier: ASCII letters, digits and `_`, not starting with a digit,
    /// no double underscore (reserved in GLSL and C), not a keyword; empty becomes
    /// `model`.
    pub fn ident(&self, raw: &str) -> String {
        let mut s = String::new();
        for ch in raw.chars() {
            let c = if ch.is_ascii_alphanumeric() { ch } else { '_' };
            if c == '_' && (s.ends_with('_') || s.is_empty()) {
                continue;
            }
            s.push(c.to_ascii_lowercase());
        }
        while s.ends_with('_') {
            s.pop();
        }
        if s.is_empty() {
            s.push_str("model");
        }
        if s.starts_with(|c: char| c.is_ascii_digit()) {
            s.insert_str(0, "m_");
        }
        if self.reserved.contains(&s.as_str()) || s.starts_with("gl_") {
            s.push_str("_m");
        }
        s
    }
}
