//! The two serialisations of ROS messages, read field by field: ROS 1
//! (little-endian, packed, strings and sequences prefixed by a `u32`
//! length) and ROS 2 CDR (a 4-byte encapsulation header, then each
//! primitive aligned to its size counted from after that header; strings
//! carry their terminating NUL in their length).

/// Why bytes could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WireError(pub String);

/// A reader over one serialised message.
#[derive(Debug)]
pub struct WireReader<'a> {
    data: &'a [u8],
    pos: usize,
    /// Where CDR alignment counts from (after the encapsulation header);
    /// `None` for ROS 1 (no alignment).
    origin: Option<usize>,
}

impl<'a> WireReader<'a> {
    /// A reader for `encoding` (`ros1` or `cdr`).
    ///
    /// # Errors
    /// An unknown encoding, or a CDR header that is not little-endian CDR.
    pub fn new(data: &'a [u8], encoding: &str) -> Result<Self, WireError> {
        match encoding {
            "ros1" => Ok(Self {
                data,
                pos: 0,
                origin: None,
            }),
            "cdr" => {
                let header = data
                    .get(..4)
                    .ok_or_else(|| WireError("shorter than the 4-byte CDR header".into()))?;
                match header[..2] {
                    [0x00, 0x01] | [0x00, 0x03] => Ok(Self {
                        data,
                        pos: 4,
                        origin: Some(4),
                    }),
                    [0x00, 0x00] | [0x00, 0x02] => {
                        Err(WireError("big-endian CDR is not supported".into()))
                    }
                    _ => Err(WireError(format!(
                        "unknown CDR encapsulation {:02x} {:02x}",
                        header[0], header[1]
                    ))),
                }
            }
            other => Err(WireError(format!(
                "unknown message encoding `{other}` (expected `cdr` or `ros1`)"
            ))),
        }
    }

    /// Whether this is CDR (ROS 2).
    pub fn is_cdr(&self) -> bool {
        self.origin.is_some()
    }

    fn align(&mut self, size: usize) {
        if let Some(origin) = self.origin {
            let rel = self.pos - origin;
            self.pos += (size - rel % size) % size;
        }
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], WireError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(WireError(format!(
                "message ends at byte {} but {n} more were needed at byte {}",
                self.data.len(),
                self.pos
            )));
        };
        let bytes = &self.data[self.pos..end];
        self.pos = end;
        Ok(bytes)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], WireError> {
        self.align(N);
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }

    /// A `u8`.
    pub fn u8(&mut self) -> Result<u8, WireError> {
        Ok(self.take(1)?[0])
    }

    /// An `i8`.
    pub fn i8(&mut self) -> Result<i8, WireError> {
        Ok(i8::from_le_bytes([self.u8()?]))
    }

    /// A `u16`.
    pub fn u16(&mut self) -> Result<u16, WireError> {
        self.array().map(u16::from_le_bytes)
    }

    /// A `u32`.
    pub fn u32(&mut self) -> Result<u32, WireError> {
        self.array().map(u32::from_le_bytes)
    }

    /// An `i32`.
    pub fn i32(&mut self) -> Result<i32, WireError> {
        self.array().map(i32::from_le_bytes)
    }

    /// An `f64`.
    pub fn f64(&mut self) -> Result<f64, WireError> {
        self.array().map(f64::from_le_bytes)
    }

    /// `N` consecutive `f64`.
    pub fn f64s<const N: usize>(&mut self) -> Result<[f64; N], WireError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64()?;
        }
        Ok(out)
    }

    /// A sequence length.
    fn length(&mut self) -> Result<usize, WireError> {
        let n = self.u32()? as usize;
        if n > self.data.len() {
            return Err(WireError(format!(
                "a length of {n} in a message of {} bytes",
                self.data.len()
            )));
        }
        Ok(n)
    }

    /// A string (CDR: its length counts a terminating NUL).
    pub fn string(&mut self) -> Result<String, WireError> {
        let n = self.length()?;
        let bytes = self.take(n)?;
        let bytes = if self.is_cdr() {
            bytes.strip_suffix(&[0]).unwrap_or(bytes)
        } else {
            bytes
        };
        String::from_utf8(bytes.to_vec())
            .map_err(|e| WireError(format!("a string is not UTF-8: {e}")))
    }

    /// A sequence of strings.
    pub fn strings(&mut self) -> Result<Vec<String>, WireError> {
        let n = self.length()?;
        (0..n).map(|_| self.string()).collect()
    }

    /// A sequence of `f64`.
    pub fn f64_seq(&mut self) -> Result<Vec<f64>, WireError> {
        let n = self.length()?;
        (0..n).map(|_| self.f64()).collect()
    }

    /// A sequence of bytes (`uint8[]`), borrowed.
    pub fn bytes(&mut self) -> Result<&'a [u8], WireError> {
        let n = self.length()?;
        self.take(n)
    }

    /// A `bool`.
    pub fn bool(&mut self) -> Result<bool, WireError> {
        Ok(self.u8()? != 0)
    }

    /// A sequence of elements read by `read`.
    pub fn seq<T>(
        &mut self,
        mut read: impl FnMut(&mut Self) -> Result<T, WireError>,
    ) -> Result<Vec<T>, WireError> {
        let n = self.length()?;
        (0..n).map(|_| read(self)).collect()
    }

    /// Checks that every byte was read (CDR may end in alignment padding).
    ///
    /// # Errors
    /// When bytes are left over (the recorded type is not what was decoded).
    pub fn finish(&self) -> Result<(), WireError> {
        let left = self.data.len() - self.pos;
        if left == 0 || (self.is_cdr() && left < 8 && self.data[self.pos..].iter().all(|b| *b == 0))
        {
            Ok(())
        } else {
            Err(WireError(format!(
                "{left} bytes left over after the last field (is the recorded type the one decoded?)"
            )))
        }
    }
}
