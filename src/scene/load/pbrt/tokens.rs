//! pbrt's tokens and parameter lists.
//!
//! A token is a quoted string (`"..."`, with `\"`, `\\`, `\n`, `\t`), `[`, `]`, or a run of
//! other non-blank characters (a directive's name, a number, `true`/`false`); `#` starts a
//! comment to the end of the line. A parameter is a quoted `"type name"` and its value: one
//! token, or a bracketed list of them.

/// A token and the 1-based line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub enum Token {
    /// A bare word: a directive, a number, `true`, `false`.
    Word(String),
    /// A quoted string, unescaped.
    Str(String),
    Open,
    Close,
}

impl Token {
    /// The token as the file spells it, for messages.
    pub fn shown(&self) -> String {
        match self {
            Token::Word(w) => format!("'{w}'"),
            Token::Str(s) => format!("\"{s}\""),
            Token::Open => "'['".into(),
            Token::Close => "']'".into(),
        }
    }
}

/// The tokens of one file's text.
pub struct Tokens<'a> {
    text: &'a [u8],
    at: usize,
    line: usize,
    peeked: Option<(Token, usize)>,
}

pub(in crate::scene::load) use crate::scene::load::common::Located;

impl<'a> Tokens<'a> {
    pub fn new(text: &'a [u8]) -> Self {
        Tokens {
            text,
            at: 0,
            line: 1,
            peeked: None,
        }
    }

    /// The next token without taking it.
    pub fn peek(&mut self) -> Result<Option<&Token>, Located> {
        if self.peeked.is_none() {
            self.peeked = self.scan()?;
        }
        Ok(self.peeked.as_ref().map(|(t, _)| t))
    }

    /// The next token and its line.
    pub fn next(&mut self) -> Result<Option<(Token, usize)>, Located> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.scan(),
        }
    }

    fn scan(&mut self) -> Result<Option<(Token, usize)>, Located> {
        let text = self.text;
        loop {
            match text.get(self.at) {
                None => return Ok(None),
                Some(b'\n') => {
                    self.line += 1;
                    self.at += 1;
                }
                Some(c) if c.is_ascii_whitespace() => self.at += 1,
                Some(b'#') => {
                    while self.at < text.len() && text[self.at] != b'\n' {
                        self.at += 1;
                    }
                }
                Some(_) => break,
            }
        }
        let line = self.line;
        let token = match text[self.at] {
            b'[' => {
                self.at += 1;
                Token::Open
            }
            b']' => {
                self.at += 1;
                Token::Close
            }
            b'"' => {
                self.at += 1;
                let mut bytes = Vec::new();
                loop {
                    match text.get(self.at) {
                        None | Some(b'\n') => {
                            return Err((line, "a string is not closed on its line (a missing '\"')".into()))
                        }
                        Some(b'"') => break,
                        Some(b'\\') => {
                            let escaped = match text.get(self.at + 1) {
                                Some(b'n') => b'\n',
                                Some(b't') => b'\t',
                                Some(b'b') => 8,
                                Some(b'f') => 12,
                                Some(b'r') => b'\r',
                                Some(&c @ (b'"' | b'\\' | b'\'')) => c,
                                _ => return Err((line, "a string has an unknown escape after '\\'".into())),
                            };
                            bytes.push(escaped);
                            self.at += 2;
                        }
                        Some(&c) => {
                            bytes.push(c);
                            self.at += 1;
                        }
                    }
                }
                self.at += 1;
                let text =
                    String::from_utf8(bytes).map_err(|_| (line, "a string is not UTF-8 text".to_string()))?;
                Token::Str(text)
            }
            _ => {
                let start = self.at;
                while let Some(&c) = text.get(self.at) {
                    if c.is_ascii_whitespace() || matches!(c, b'[' | b']' | b'"' | b'#') {
                        break;
                    }
                    self.at += 1;
                }
                let word = std::str::from_utf8(&text[start..self.at])
                    .map_err(|_| (line, "the file is not UTF-8 text".to_string()))?;
                Token::Word(word.to_string())
            }
        };
        Ok(Some((token, line)))
    }

    /// A number, for a directive's arguments (`Translate 1 2 3`).
    pub fn number(&mut self, directive: &str) -> Result<f64, Located> {
        match self.next()? {
            Some((Token::Word(w), line)) => {
                parse_number(&w).ok_or_else(|| (line, format!("{directive}: '{w}' is not a number")))
            }
            Some((t, line)) => Err((
                line,
                format!("{directive}: expected a number, found {}", t.shown()),
            )),
            None => Err((
                self.line,
                format!("{directive}: expected a number, found the end of the file"),
            )),
        }
    }

    /// `count` numbers, bracketed or not (`Transform [ ... ]`, `LookAt ...`).
    pub fn numbers(&mut self, directive: &str, count: usize) -> Result<Vec<f64>, Located> {
        let bracketed = self.peek()? == Some(&Token::Open);
        if bracketed {
            self.next()?;
        }
        let numbers = (0..count)
            .map(|_| self.number(directive))
            .collect::<Result<Vec<_>, _>>()?;
        if bracketed {
            match self.next()? {
                Some((Token::Close, _)) => {}
                Some((t, line)) => {
                    return Err((
                        line,
                        format!(
                            "{directive}: expected {count} numbers and ']', found {}",
                            t.shown()
                        ),
                    ))
                }
                None => {
                    return Err((
                        self.line,
                        format!("{directive}: expected ']', found the end of the file"),
                    ))
                }
            }
        }
        Ok(numbers)
    }

    /// A quoted string, for a directive's arguments (`Shape "sphere"`).
    pub fn string(&mut self, directive: &str) -> Result<String, Located> {
        match self.next()? {
            Some((Token::Str(s), _)) => Ok(s),
            Some((t, line)) => Err((
                line,
                format!("{directive}: expected a quoted string, found {}", t.shown()),
            )),
            None => Err((
                self.line,
                format!("{directive}: expected a quoted string, found the end of the file"),
            )),
        }
    }

    /// The parameter list that follows a directive: `"type name" value` pairs up to the next
    /// bare word (the next directive) or the end.
    pub fn parameters(&mut self, directive: &str) -> Result<Params, Located> {
        let mut params = Vec::new();
        while let Some(Token::Str(_)) = self.peek()? {
            let Some((Token::Str(declaration), line)) = self.next()? else {
                unreachable!()
            };
            params.push(self.parameter(directive, &declaration, line)?);
        }
        Ok(Params(params))
    }

    /// One parameter's value, after its declaration.
    pub fn parameter(&mut self, directive: &str, declaration: &str, line: usize) -> Result<Param, Located> {
        let words: Vec<&str> = declaration.split_whitespace().collect();
        let [ty, name] = words[..] else {
            return Err((
                line,
                format!("{directive}: parameter \"{declaration}\" is not \"type name\""),
            ));
        };
        let mut values = Vec::new();
        let mut value = |token: Token, line: usize| -> Result<(), Located> {
            values.push(match token {
                Token::Str(s) => Value::Str(s),
                Token::Word(w) => match w.as_str() {
                    "true" => Value::Bool(true),
                    "false" => Value::Bool(false),
                    _ => Value::Num(parse_number(&w).ok_or_else(|| {
                        (
                            line,
                            format!("{directive}: \"{declaration}\": '{w}' is not a value"),
                        )
                    })?),
                },
                t => {
                    return Err((
                        line,
                        format!("{directive}: \"{declaration}\": unexpected {}", t.shown()),
                    ))
                }
            });
            Ok(())
        };
        match self.next()? {
            Some((Token::Open, _)) => loop {
                match self.next()? {
                    Some((Token::Close, _)) => break,
                    Some((t, line)) => value(t, line)?,
                    None => {
                        return Err((
                            line,
                            format!("{directive}: \"{declaration}\": the list has no closing ']'"),
                        ))
                    }
                }
            },
            Some((t @ (Token::Str(_) | Token::Word(_)), line)) => value(t, line)?,
            Some((t, line)) => {
                return Err((
                    line,
                    format!(
                        "{directive}: \"{declaration}\": expected a value, found {}",
                        t.shown()
                    ),
                ))
            }
            None => return Err((line, format!("{directive}: \"{declaration}\" has no value"))),
        }
        Ok(Param {
            ty: ty.to_string(),
            name: name.to_string(),
            values,
            line,
        })
    }
}

/// A number as pbrt writes them (`1`, `-2.5`, `1e-3`, `.5`).
fn parse_number(word: &str) -> Option<f64> {
    let first = word.as_bytes().first()?;
    if !(first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.')) {
        return None;
    }
    word.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// One value of a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Num(f64),
    Str(String),
    Bool(bool),
}

/// A parameter: its type, name, values and line.
#[derive(Clone, Debug)]
pub struct Param {
    pub ty: String,
    pub name: String,
    pub values: Vec<Value>,
    pub line: usize,
}

/// A directive's parameters.
#[derive(Clone, Debug, Default)]
pub struct Params(pub Vec<Param>);

impl Params {
    fn find(&self, name: &str) -> Option<&Param> {
        self.0.iter().rev().find(|p| p.name == name)
    }

    /// Whether a parameter of this name is there.
    pub fn has(&self, name: &str) -> bool {
        self.find(name).is_some()
    }

    /// The numbers of parameter `name`, if it is there; an error if it holds anything else.
    pub fn numbers(&self, name: &str) -> Result<Option<Vec<f64>>, Located> {
        let Some(p) = self.find(name) else { return Ok(None) };
        p.values
            .iter()
            .map(|v| match v {
                Value::Num(x) => Ok(*x),
                _ => Err((p.line, format!("\"{} {}\" must hold numbers", p.ty, p.name))),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// Parameter `name`'s one number, or `default`.
    pub fn number(&self, name: &str, default: f64) -> Result<f64, Located> {
        match self.numbers(name)? {
            None => Ok(default),
            Some(v) if v.len() == 1 => Ok(v[0]),
            Some(v) => Err((
                self.find(name).map_or(0, |p| p.line),
                format!("\"{name}\" must be one number, not {}", v.len()),
            )),
        }
    }

    /// Parameter `name` as points (its numbers in threes).
    pub fn points(&self, name: &str) -> Result<Option<Vec<glam::DVec3>>, Located> {
        let Some(numbers) = self.numbers(name)? else {
            return Ok(None);
        };
        if numbers.len() % 3 != 0 {
            let line = self.find(name).map_or(0, |p| p.line);
            return Err((
                line,
                format!("\"{name}\" holds {} numbers, not a multiple of 3", numbers.len()),
            ));
        }
        Ok(Some(
            numbers
                .chunks_exact(3)
                .map(|c| glam::DVec3::new(c[0], c[1], c[2]))
                .collect(),
        ))
    }

    /// Parameter `name` as whole numbers of at least 0 (indices, counts).
    pub fn integers(&self, name: &str) -> Result<Option<Vec<u64>>, Located> {
        let Some(numbers) = self.numbers(name)? else {
            return Ok(None);
        };
        let line = self.find(name).map_or(0, |p| p.line);
        numbers
            .iter()
            .map(|&x| {
                if x >= 0.0 && x.fract() == 0.0 && x < 2f64.powi(53) {
                    Ok(x as u64)
                } else {
                    Err((
                        line,
                        format!("\"{name}\" must hold whole numbers of at least 0, not {x}"),
                    ))
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// Parameter `name`'s one string, if it is there.
    pub fn string(&self, name: &str) -> Result<Option<String>, Located> {
        let Some(p) = self.find(name) else { return Ok(None) };
        match &p.values[..] {
            [Value::Str(s)] => Ok(Some(s.clone())),
            _ => Err((p.line, format!("\"{} {}\" must be one string", p.ty, p.name))),
        }
    }

    /// The line of parameter `name`, or `fallback`.
    pub fn line_of(&self, name: &str, fallback: usize) -> usize {
        self.find(name).map_or(fallback, |p| p.line)
    }
}
