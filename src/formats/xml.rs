//! A small pull scanner for the XML that instrument formats carry (ISO 25178-71 `main.xml`):
//! elements and text only (docs/formats.md).
//!
//! Written from the W3C XML 1.0 grammar, reduced to what a data header needs: start, end and
//! empty-element tags (attributes are parsed for well-formedness and dropped), character data
//! with the five predefined entities and numeric character references, CDATA sections;
//! comments, processing instructions and the XML declaration are skipped. A `<!DOCTYPE>`
//! without an internal subset is skipped; one with an internal subset (`[...]`) is refused,
//! so no entity can expand (no "billion laughs"). Element names are returned without their
//! namespace prefix (`p:ISO5436_2` → `ISO5436_2`). Nesting is checked (every end tag must match
//! its start tag, one root element) and capped at [`MAX_DEPTH`] levels. Nothing is allocated
//! beyond the text that is returned, so memory stays proportional to the input.
use std::borrow::Cow;

/// Deepest element nesting accepted; real headers use fewer than 10 levels.
pub const MAX_DEPTH: usize = 256;

/// What the scanner found next.
#[derive(Debug, Clone, PartialEq)]
pub enum Event<'a> {
    /// A start tag (also emitted for `<x/>`, followed by its `End`), local name.
    Start(&'a str),
    /// An end tag, local name.
    End(&'a str),
    /// Character data inside an element (entities decoded; may be whitespace only).
    Text(Cow<'a, str>),
}

/// Malformed XML: byte offset in the document and what is wrong there.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("malformed XML at byte {offset}: {reason}")]
pub struct XmlError {
    pub offset: usize,
    pub reason: String,
}

/// Pull scanner over a whole document.
pub struct Scanner<'a> {
    s: &'a str,
    pos: usize,
    stack: Vec<&'a str>,
    pending_end: Option<&'a str>,
    root_closed: bool,
    failed: bool,
}

impl<'a> Scanner<'a> {
    pub fn new(s: &'a str) -> Self {
        let s = s.strip_prefix('\u{feff}').unwrap_or(s);
        Scanner {
            s,
            pos: 0,
            stack: Vec::new(),
            pending_end: None,
            root_closed: false,
            failed: false,
        }
    }

    /// The names of the open elements, outermost first.
    pub fn open_elements(&self) -> &[&'a str] {
        &self.stack
    }

    fn err(&mut self, reason: impl Into<String>) -> Option<Result<Event<'a>, XmlError>> {
        self.failed = true;
        Some(Err(XmlError {
            offset: self.pos,
            reason: reason.into(),
        }))
    }

    /// Skips to just after `end`, or fails with `what` if it never comes.
    fn skip_past(&mut self, end: &str) -> bool {
        match self.s[self.pos..].find(end) {
            Some(k) => {
                self.pos += k + end.len();
                true
            }
            None => false,
        }
    }

    fn step(&mut self) -> Option<Result<Event<'a>, XmlError>> {
        if let Some(name) = self.pending_end.take() {
            return Some(Ok(self.close(name)));
        }
        let s: &'a str = self.s;
        let rest = &s[self.pos..];
        if rest.is_empty() {
            return match self.stack.last() {
                Some(open) => {
                    let reason = format!("document ends inside <{open}> (truncated?)");
                    self.err(reason)
                }
                None if !self.root_closed => self.err("no root element"),
                None => None,
            };
        }
        if !rest.starts_with('<') {
            let len = rest.find('<').unwrap_or(rest.len());
            let raw = &rest[..len];
            if self.stack.is_empty() {
                if !raw.trim().is_empty() {
                    return self.err("text outside the root element");
                }
                self.pos += len;
                return self.step();
            }
            return match decode_entities(raw) {
                Ok(text) => {
                    self.pos += len;
                    Some(Ok(Event::Text(text)))
                }
                Err(reason) => self.err(reason),
            };
        }
        if rest.starts_with("<?") {
            if !self.skip_past("?>") {
                return self.err("unterminated processing instruction");
            }
            return self.step();
        }
        if rest.starts_with("<!--") {
            if !self.skip_past("-->") {
                return self.err("unterminated comment");
            }
            return self.step();
        }
        if let Some(body) = rest.strip_prefix("<![CDATA[") {
            if self.stack.is_empty() {
                return self.err("CDATA outside the root element");
            }
            return match body.find("]]>") {
                Some(k) => {
                    self.pos += "<![CDATA[".len() + k + 3;
                    Some(Ok(Event::Text(Cow::Borrowed(&body[..k]))))
                }
                None => self.err("unterminated CDATA section"),
            };
        }
        if rest.starts_with("<!DOCTYPE") {
            let end = rest.find('>');
            let subset = rest.find('[');
            return match (end, subset) {
                (Some(e), Some(b)) if b < e => {
                    self.err("DTD internal subsets (entity declarations) are not read")
                }
                (Some(e), _) => {
                    self.pos += e + 1;
                    self.step()
                }
                (None, _) => self.err("unterminated DOCTYPE"),
            };
        }
        if let Some(body) = rest.strip_prefix("</") {
            let Some(k) = body.find('>') else {
                return self.err("unterminated end tag");
            };
            let name = local_name(body[..k].trim_end());
            return match self.stack.last() {
                Some(&open) if open == name => {
                    self.pos += 2 + k + 1;
                    Some(Ok(self.close(name)))
                }
                Some(&open) => self.err(format!("</{name}> closes <{open}>")),
                None => self.err(format!("</{name}> without a start tag")),
            };
        }
        self.start_tag()
    }

    fn close(&mut self, name: &'a str) -> Event<'a> {
        self.stack.pop();
        if self.stack.is_empty() {
            self.root_closed = true;
        }
        Event::End(name)
    }

    fn start_tag(&mut self) -> Option<Result<Event<'a>, XmlError>> {
        let s = self.s;
        let start = self.pos + 1;
        let bytes = s.as_bytes();
        let mut at = start;
        while at < bytes.len() && !matches!(bytes[at], b' ' | b'\t' | b'\r' | b'\n' | b'/' | b'>') {
            at += 1;
        }
        let full_name = &s[start..at];
        if full_name.is_empty() || !is_name_start(full_name) {
            return self.err("a `<` that starts no tag");
        }
        // Attributes: name = "value" pairs; a quoted value may contain `>`.
        let empty = loop {
            while at < bytes.len() && bytes[at].is_ascii_whitespace() {
                at += 1;
            }
            match bytes.get(at) {
                None => return self.err(format!("unterminated start tag <{full_name}")),
                Some(b'>') => break false,
                Some(b'/') if bytes.get(at + 1) == Some(&b'>') => {
                    at += 1;
                    break true;
                }
                Some(_) => {
                    let Some(eq) = s[at..].find('=') else {
                        return self.err(format!("attribute without value in <{full_name}>"));
                    };
                    let mut q = at + eq + 1;
                    while q < bytes.len() && bytes[q].is_ascii_whitespace() {
                        q += 1;
                    }
                    let quote = match bytes.get(q) {
                        Some(&c @ (b'"' | b'\'')) => c as char,
                        _ => return self.err(format!("unquoted attribute in <{full_name}>")),
                    };
                    let Some(close) = s[q + 1..].find(quote) else {
                        return self.err(format!("unterminated attribute in <{full_name}>"));
                    };
                    at = q + 1 + close + 1;
                }
            }
        };
        if self.root_closed {
            return self.err(format!("second root element <{full_name}>"));
        }
        if self.stack.len() >= MAX_DEPTH {
            return self.err(format!("elements nested deeper than {MAX_DEPTH} levels"));
        }
        self.pos = at + 1;
        let name = local_name(full_name);
        self.stack.push(name);
        if empty {
            self.pending_end = Some(name);
        }
        Some(Ok(Event::Start(name)))
    }
}

impl<'a> Iterator for Scanner<'a> {
    type Item = Result<Event<'a>, XmlError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        self.step()
    }
}

fn is_name_start(name: &str) -> bool {
    name.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_' || c == ':')
}

fn local_name(name: &str) -> &str {
    name.rsplit(':').next().unwrap_or(name)
}

/// Character data with the predefined entities and character references replaced.
fn decode_entities(raw: &str) -> Result<Cow<'_, str>, String> {
    if !raw.contains('&') {
        return Ok(Cow::Borrowed(raw));
    }
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(k) = rest.find('&') {
        out.push_str(&rest[..k]);
        let after = &rest[k + 1..];
        let end = after
            .find(';')
            .filter(|&e| e <= 10)
            .ok_or_else(|| "`&` that starts no entity".to_string())?;
        let entity = &after[..end];
        let c = match entity {
            "lt" => '<',
            "gt" => '>',
            "amp" => '&',
            "quot" => '"',
            "apos" => '\'',
            _ => {
                let code = if let Some(hex) = entity.strip_prefix("#x") {
                    u32::from_str_radix(hex, 16).ok()
                } else if let Some(dec) = entity.strip_prefix('#') {
                    dec.parse::<u32>().ok()
                } else {
                    None
                };
                code.and_then(char::from_u32)
                    .ok_or_else(|| format!("unknown entity `&{entity};`"))?
            }
        };
        out.push(c);
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(Cow::Owned(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events(s: &str) -> Result<Vec<Event<'_>>, XmlError> {
        Scanner::new(s).collect()
    }

    #[test]
    fn elements_text_entities_and_skipped_parts() {
        let doc = "\u{feff}<?xml version=\"1.0\"?>\n<!-- c --><!DOCTYPE r>\
                   <p:r xmlns:p=\"u>v\"><a k='1'>x &lt; y &#65;&#x42;</a><b/>\
                   <c><![CDATA[<raw>]]></c></p:r>\n";
        let ev = events(doc).unwrap();
        use Event::*;
        assert_eq!(
            ev,
            vec![
                Start("r"),
                Start("a"),
                Text(Cow::Owned("x < y AB".into())),
                End("a"),
                Start("b"),
                End("b"),
                Start("c"),
                Text(Cow::Borrowed("<raw>")),
                End("c"),
                End("r"),
            ]
        );
    }

    #[test]
    fn malformed_documents_are_errors() {
        for (doc, want) in [
            ("<a><b></a>", "closes"),
            ("<a>", "truncated"),
            ("<a></a><b></b>", "second root"),
            ("x<a/>", "outside"),
            ("<a>&bogus;</a>", "unknown entity"),
            ("<!DOCTYPE a [<!ENTITY x \"y\">]><a/>", "internal subset"),
            ("<a b=c/>", "unquoted"),
            ("<a><!-- x</a>", "comment"),
            ("", "no root"),
            ("<a", "unterminated start tag"),
            ("<a>< b</a>", "starts no tag"),
        ] {
            let err = events(doc).unwrap_err();
            assert!(err.reason.contains(want), "{doc}: {err}");
        }
        let deep = "<a>".repeat(MAX_DEPTH + 1);
        assert!(events(&deep).unwrap_err().reason.contains("deeper"));
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let doc = "<r><a x=\"1\">t&amp;</a><b/><![CDATA[z]]><!-- q --></r>";
        for cut in 0..doc.len() {
            assert!(events(&doc[..cut]).is_err(), "cut at {cut}");
        }
        assert!(events(doc).is_ok());
    }
}
