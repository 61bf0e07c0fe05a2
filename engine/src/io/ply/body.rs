//! PLY body: typed values from ASCII lines or packed binary, behind one interface.
//!
//! Every read is bounds-checked and reports the end of the data as
//! [`BodyError::End`] (never a panic); callers add the element and record.

use super::header::{Element, PropertyType, Scalar};

/// A problem reading one value.
#[derive(Debug)]
pub(crate) enum BodyError {
    /// The data ends before the value.
    End,
    /// The value is malformed: 1-based line (0 in binary bodies) and what is wrong.
    Bad(usize, String),
}

/// Reads typed values record by record.
pub(crate) trait ValueReader {
    /// Starts the next record (ASCII: the next non-blank line).
    fn begin_record(&mut self) -> Result<(), BodyError>;
    /// Reads a value of any type as f64.
    fn float(&mut self, ty: Scalar) -> Result<f64, BodyError>;
    /// Reads a value of integer type as i64 (no wrapping: a `uint` stays positive).
    fn int(&mut self, ty: Scalar) -> Result<i64, BodyError>;
    /// Skips `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: usize) -> Result<(), BodyError>;
    /// Ends the record (ASCII: no values may be left on the line).
    fn end_record(&mut self) -> Result<(), BodyError>;
    /// 1-based line of the current record, 0 for binary bodies.
    fn line(&self) -> usize;

    /// Reads a list length and checks that it is not negative.
    fn list_len(&mut self, ty: Scalar) -> Result<usize, BodyError> {
        let n = self.int(ty)?;
        usize::try_from(n)
            .map_err(|_| BodyError::Bad(self.line(), format!("negative list length {n}")))
    }

    /// Skips a whole record of `element`.
    fn skip_record(&mut self, element: &Element) -> Result<(), BodyError> {
        self.begin_record()?;
        for p in &element.properties {
            match p.ty {
                PropertyType::Scalar(s) => self.skip(s, 1)?,
                PropertyType::List { count, item } => {
                    let n = self.list_len(count)?;
                    self.skip(item, n)?;
                }
            }
        }
        self.end_record()
    }
}

/// ASCII body: one record per line, values separated by whitespace.
pub(crate) struct AsciiReader<'a> {
    data: &'a [u8],
    pos: usize,
    /// Line number of the line most recently started.
    line: usize,
    tokens: std::str::SplitAsciiWhitespace<'a>,
}

impl<'a> AsciiReader<'a> {
    /// A reader over `data`, whose first line is line `first_line` of the file.
    pub(crate) fn new(data: &'a [u8], first_line: usize) -> Self {
        Self {
            data,
            pos: 0,
            line: first_line.saturating_sub(1),
            tokens: "".split_ascii_whitespace(),
        }
    }

    fn token(&mut self) -> Result<&'a str, BodyError> {
        self.tokens.next().ok_or_else(|| {
            BodyError::Bad(
                self.line,
                "fewer values than the header declares".to_owned(),
            )
        })
    }
}

impl ValueReader for AsciiReader<'_> {
    fn begin_record(&mut self) -> Result<(), BodyError> {
        loop {
            if self.pos >= self.data.len() {
                return Err(BodyError::End);
            }
            let rest = &self.data[self.pos..];
            let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let raw = &rest[..len];
            self.pos += len + 1;
            self.line += 1;
            let text = std::str::from_utf8(raw)
                .map_err(|_| BodyError::Bad(self.line, "line is not text".to_owned()))?;
            self.tokens = text.split_ascii_whitespace();
            if self.tokens.clone().next().is_some() {
                return Ok(());
            }
        }
    }

    fn float(&mut self, _ty: Scalar) -> Result<f64, BodyError> {
        let token = self.token()?;
        token
            .parse::<f64>()
            .map_err(|_| BodyError::Bad(self.line, format!("`{token}` is not a number")))
    }

    fn int(&mut self, _ty: Scalar) -> Result<i64, BodyError> {
        let token = self.token()?;
        if let Ok(v) = token.parse::<i64>() {
            return Ok(v);
        }
        // Some writers print integers as `3.0`; accept exact integral values only.
        match token.parse::<f64>() {
            Ok(v) if v.fract() == 0.0 && v.abs() < 9.0e15 => Ok(v as i64),
            _ => Err(BodyError::Bad(
                self.line,
                format!("`{token}` is not an integer"),
            )),
        }
    }

    fn skip(&mut self, _ty: Scalar, n: usize) -> Result<(), BodyError> {
        for _ in 0..n {
            self.token()?;
        }
        Ok(())
    }

    fn end_record(&mut self) -> Result<(), BodyError> {
        match self.tokens.next() {
            None => Ok(()),
            Some(extra) => Err(BodyError::Bad(
                self.line,
                format!("more values than the header declares (first extra: `{extra}`)"),
            )),
        }
    }

    fn line(&self) -> usize {
        self.line
    }
}

/// Binary body, little- or big-endian.
pub(crate) struct BinaryReader<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl<'a> BinaryReader<'a> {
    /// A reader over `data`.
    pub(crate) fn new(data: &'a [u8], big_endian: bool) -> Self {
        Self {
            data,
            pos: 0,
            big_endian,
        }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], BodyError> {
        let end = self.pos.checked_add(n).ok_or(BodyError::End)?;
        let bytes = self.data.get(self.pos..end).ok_or(BodyError::End)?;
        self.pos = end;
        Ok(bytes)
    }

    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], BodyError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N)?);
        if self.big_endian {
            out.reverse();
        }
        Ok(out) // now little-endian
    }
}

impl ValueReader for BinaryReader<'_> {
    fn begin_record(&mut self) -> Result<(), BodyError> {
        Ok(())
    }

    fn float(&mut self, ty: Scalar) -> Result<f64, BodyError> {
        Ok(match ty {
            Scalar::F32 => f64::from(f32::from_le_bytes(self.bytes()?)),
            Scalar::F64 => f64::from_le_bytes(self.bytes()?),
            _ => self.int(ty)? as f64,
        })
    }

    fn int(&mut self, ty: Scalar) -> Result<i64, BodyError> {
        Ok(match ty {
            Scalar::I8 => i64::from(i8::from_le_bytes(self.bytes()?)),
            Scalar::U8 => i64::from(u8::from_le_bytes(self.bytes()?)),
            Scalar::I16 => i64::from(i16::from_le_bytes(self.bytes()?)),
            Scalar::U16 => i64::from(u16::from_le_bytes(self.bytes()?)),
            Scalar::I32 => i64::from(i32::from_le_bytes(self.bytes()?)),
            Scalar::U32 => i64::from(u32::from_le_bytes(self.bytes()?)),
            // Not reached for validated headers (lengths and indices are integers);
            // saturating `as` keeps a float from panicking or wrapping.
            Scalar::F32 | Scalar::F64 => self.float(ty)? as i64,
        })
    }

    fn skip(&mut self, ty: Scalar, n: usize) -> Result<(), BodyError> {
        self.take(n.checked_mul(ty.size()).ok_or(BodyError::End)?)
            .map(|_| ())
    }

    fn end_record(&mut self) -> Result<(), BodyError> {
        Ok(())
    }

    fn line(&self) -> usize {
        0
    }
}
