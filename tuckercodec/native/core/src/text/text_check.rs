//! The checks of a text file read a chunk at a time (`tuckercodec/io/obj.py`
//! `_read_checked`): refused at the first NUL byte, the first byte that is not UTF-8, or the
//! first line longer than a limit, naming the line, before any more is read.

/// Why a text was refused, and on which 1-based line (line ends: `\n`, `\r\n`, a lone `\r`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TextFault {
    /// What is wrong.
    pub kind: FaultKind,
    /// The 1-based line at fault.
    pub line: u64,
}

/// The kinds of [`TextFault`], each with its own message on the Python side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// A NUL byte: binary data.
    Nul,
    /// Bytes that are not UTF-8.
    NotUtf8,
    /// A line longer than the limit.
    TooLong,
    /// The text ends inside a UTF-8 character.
    EndsInsideCharacter,
}

impl FaultKind {
    /// A short name, which the Python side maps to its message.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Nul => "nul",
            FaultKind::NotUtf8 => "utf8",
            FaultKind::TooLong => "long",
            FaultKind::EndsInsideCharacter => "truncated",
        }
    }
}

/// The state of the checks between chunks. Feed the chunks in order with [`TextCheck::feed`],
/// then call [`TextCheck::finish`]; results are the Python reference's for the same chunks.
#[derive(Debug, Clone)]
pub struct TextCheck {
    limit: u64,
    /// The number of the line the next chunk starts in.
    line: u64,
    /// Bytes of that line in the chunks before.
    line_length: u64,
    /// The chunk before ended in `\r`: a `\n` first in the next one ends no line.
    after_cr: bool,
    /// The start of a UTF-8 character that the chunk before ended inside.
    pending: Vec<u8>,
}

impl TextCheck {
    /// Checks with lines of at most `limit` bytes (their line end not counted).
    pub fn new(limit: u64) -> TextCheck {
        TextCheck {
            limit,
            line: 1,
            line_length: 0,
            after_cr: false,
            pending: Vec::new(),
        }
    }

    fn fault(&self, kind: FaultKind, chunk: &[u8], offset: usize) -> TextFault {
        let before = chunk.get(..offset).unwrap_or(chunk);
        TextFault {
            kind,
            line: self.line.saturating_add(line_ends(before, self.after_cr)),
        }
    }

    /// Checks the next chunk.
    pub fn feed(&mut self, chunk: &[u8]) -> Result<(), TextFault> {
        if count_byte(chunk, 0) > 0 {
            let nul = chunk.iter().position(|&c| c == 0).unwrap_or(0);
            return Err(self.fault(FaultKind::Nul, chunk, nul));
        }
        if !chunk.is_ascii() || !self.pending.is_empty() {
            self.check_utf8(chunk)?;
        }
        let length = chunk.len() as u64;
        match chunk.iter().rposition(|&c| c == b'\n' || c == b'\r') {
            None => self.line_length = self.line_length.saturating_add(length),
            Some(last_end) => {
                let first_end = chunk
                    .iter()
                    .position(|&c| c == b'\n' || c == b'\r')
                    .unwrap_or(last_end);
                if self.line_length.saturating_add(first_end as u64) > self.limit {
                    return Err(self.fault(FaultKind::TooLong, chunk, 0));
                }
                self.line_length = (chunk.len() - last_end - 1) as u64;
            }
        }
        if self.line_length > self.limit {
            return Err(self.fault(FaultKind::TooLong, chunk, chunk.len()));
        }
        self.line = self.line.saturating_add(line_ends(chunk, self.after_cr));
        self.after_cr = chunk.last() == Some(&b'\r');
        Ok(())
    }

    /// Validates `chunk` as UTF-8 after the pending bytes, keeping an unfinished character.
    fn check_utf8(&mut self, chunk: &[u8]) -> Result<(), TextFault> {
        let kept = self.pending.len();
        let mut joined = std::mem::take(&mut self.pending);
        joined.extend_from_slice(chunk);
        match std::str::from_utf8(&joined) {
            Ok(_) => Ok(()),
            Err(error) if error.error_len().is_none() => {
                // a valid start of a character at the end: kept for the next chunk
                self.pending = joined.get(error.valid_up_to()..).unwrap_or(&[]).to_vec();
                Ok(())
            }
            Err(error) => {
                let at = error.valid_up_to().saturating_sub(kept);
                Err(self.fault(FaultKind::NotUtf8, chunk, at))
            }
        }
    }

    /// Checks the end of the text: it must not end inside a character.
    pub fn finish(&self) -> Result<(), TextFault> {
        if self.pending.is_empty() {
            Ok(())
        } else {
            Err(TextFault {
                kind: FaultKind::EndsInsideCharacter,
                line: self.line,
            })
        }
    }
}

/// The number of line ends in `data`: `\n`, `\r\n` or a lone `\r`; `after_cr`: the bytes
/// before ended in `\r` (so a `\n` first here is the second half of a `\r\n`).
pub fn line_ends(data: &[u8], after_cr: bool) -> u64 {
    // counted as "\n" + "\r" - "\r\n": loops the compiler vectorizes
    let newlines = count_byte(data, b'\n');
    let returns = count_byte(data, b'\r');
    let pairs = if returns == 0 {
        0
    } else {
        data.windows(2).filter(|pair| pair == b"\r\n").count()
    };
    let split_pair = usize::from(after_cr && data.first() == Some(&b'\n'));
    (newlines + returns - pairs - split_pair) as u64
}

/// How many times `byte` occurs in `data`: counted in blocks of 255 in u8 lanes, which the
/// compiler vectorizes (16 or 32 bytes a step, where a plain count takes 4).
pub fn count_byte(data: &[u8], byte: u8) -> usize {
    data.chunks(255)
        .map(|block| {
            let found = block
                .iter()
                .fold(0u8, |total, &c| total.wrapping_add(u8::from(c == byte)));
            usize::from(found)
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::{line_ends, FaultKind, TextCheck};

    #[test]
    fn counts_lines() {
        assert_eq!(line_ends(b"a\nb\r\nc\rd", false), 3);
        assert_eq!(line_ends(b"\nx", true), 0);
        assert_eq!(line_ends(b"\r\r\n\n", false), 3);
    }

    #[test]
    fn refuses() {
        let mut check = TextCheck::new(100);
        assert_eq!(check.feed(b"v 1\nv\x002").unwrap_err().line, 2);
        let mut check = TextCheck::new(4);
        assert!(check.feed(b"ab\n").is_ok());
        let fault = check.feed(b"abcde").unwrap_err();
        assert_eq!((fault.kind, fault.line), (FaultKind::TooLong, 2));
        let mut check = TextCheck::new(100);
        assert!(check.feed(b"a\n\xc3").is_ok());
        assert!(check.feed(b"\xa9\n").is_ok());
        assert!(check.feed(b"\xe2\x82").is_ok());
        assert_eq!(
            check.finish().unwrap_err().kind,
            FaultKind::EndsInsideCharacter
        );
        let mut check = TextCheck::new(100);
        let fault = check.feed(b"a\n\n\xff").unwrap_err();
        assert_eq!((fault.kind, fault.line), (FaultKind::NotUtf8, 3));
    }
}
