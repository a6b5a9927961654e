//! OMG CDR (XCDR version 1, little-endian), the serialisation ROS 2 puts on the wire and in
//! its bags: a 4-byte encapsulation header (`00 01 00 00`, "CDR_LE"), then each primitive
//! aligned to its own size counted from the end of that header; a string is its length
//! including a terminating NUL (`u32`), its bytes and the NUL; a sequence is its count
//! (`u32`) and its elements; a `bool` is one byte.

use crate::Error;

/// The encapsulation header of little-endian plain CDR.
pub const CDR_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Writes CDR, header included.
#[derive(Clone, Debug)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Default for Writer {
    fn default() -> Self {
        Self::new()
    }
}

impl Writer {
    /// A writer holding only the encapsulation header.
    pub fn new() -> Self {
        Self {
            buf: CDR_LE.to_vec(),
        }
    }

    fn align(&mut self, n: usize) {
        while !(self.buf.len() - CDR_LE.len()).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    /// A `uint8` (or `byte`, `char`).
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    /// An `int8`.
    pub fn i8(&mut self, v: i8) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `bool`.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }
    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `float32`.
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// A `string`.
    pub fn string(&mut self, s: &str) {
        self.len(s.len() + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }
    /// A sequence's length.
    ///
    /// # Panics
    /// If `n` exceeds `u32::MAX`, which no message of a map comes near.
    pub fn len(&mut self, n: usize) {
        self.u32(u32::try_from(n).expect("a CDR sequence of at most u32::MAX elements"));
    }
    /// A `uint8[]` (or `int8[]` as bytes).
    pub fn bytes(&mut self, b: &[u8]) {
        self.len(b.len());
        self.buf.extend_from_slice(b);
    }
    /// The message: header and body.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

/// Reads CDR, header included.
#[derive(Clone, Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// A reader of `bytes`, which must start with a little-endian CDR header.
    ///
    /// # Errors
    /// [`Error::Decode`] when the header is missing or names another encoding.
    pub fn new(bytes: &'a [u8]) -> Result<Self, Error> {
        match bytes {
            [0x00, 0x01, _, _, ..] => Ok(Self { bytes, at: 4 }),
            [a, b, _, _, ..] => Err(Error::Decode(format!(
                "encapsulation {a:02x} {b:02x} is not little-endian plain CDR (00 01)"
            ))),
            _ => Err(Error::Decode(format!(
                "{} bytes: shorter than the CDR header",
                bytes.len()
            ))),
        }
    }

    fn take(&mut self, n: usize, align: usize) -> Result<&'a [u8], Error> {
        while !(self.at - 4).is_multiple_of(align) {
            self.at += 1;
        }
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(Error::Decode(format!(
                "{} bytes wanted at byte {} of {}",
                n,
                self.at,
                self.bytes.len()
            )));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    /// A `uint8`.
    pub fn u8(&mut self) -> Result<u8, Error> {
        Ok(self.take(1, 1)?[0])
    }
    /// An `int8`.
    pub fn i8(&mut self) -> Result<i8, Error> {
        Ok(i8::from_le_bytes([self.u8()?]))
    }
    /// A `bool`.
    pub fn bool(&mut self) -> Result<bool, Error> {
        Ok(self.u8()? != 0)
    }
    /// An `int32`.
    pub fn i32(&mut self) -> Result<i32, Error> {
        Ok(i32::from_le_bytes(self.take(4, 4)?.try_into().expect("4")))
    }
    /// A `uint32`.
    pub fn u32(&mut self) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.take(4, 4)?.try_into().expect("4")))
    }
    /// A `float32`.
    pub fn f32(&mut self) -> Result<f32, Error> {
        Ok(f32::from_le_bytes(self.take(4, 4)?.try_into().expect("4")))
    }
    /// A `float64`.
    pub fn f64(&mut self) -> Result<f64, Error> {
        Ok(f64::from_le_bytes(self.take(8, 8)?.try_into().expect("8")))
    }
    /// A sequence's length, refused when the bytes left cannot hold that many elements of
    /// at least `min_size` bytes each (a corrupt length must not allocate).
    pub fn len(&mut self, min_size: usize) -> Result<usize, Error> {
        let n = self.u32()? as usize;
        let left = self.bytes.len() - self.at;
        if n.saturating_mul(min_size.max(1)) > left {
            return Err(Error::Decode(format!(
                "a sequence of {n} elements in {left} bytes"
            )));
        }
        Ok(n)
    }
    /// A `string`.
    pub fn string(&mut self) -> Result<String, Error> {
        let n = self.len(1)?;
        let b = self.take(n, 1)?;
        let b = b.strip_suffix(&[0]).unwrap_or(b);
        String::from_utf8(b.to_vec()).map_err(|e| Error::Decode(format!("a string: {e}")))
    }
    /// A `uint8[]`.
    pub fn bytes(&mut self) -> Result<&'a [u8], Error> {
        let n = self.len(1)?;
        self.take(n, 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_are_aligned_to_their_size_from_the_end_of_the_header() {
        let mut w = Writer::new();
        w.u8(7);
        w.f64(1.5);
        w.string("ab");
        w.i32(-2);
        let b = w.finish();
        // header 4 | u8 at 4 | pad to 8 from the body's start (body offset 8) | f64 |
        // u32 3 "ab\0" | pad to 4 | i32
        assert_eq!(&b[..4], &CDR_LE);
        assert_eq!(b[4], 7);
        assert_eq!(&b[5..12], &[0; 7]);
        assert_eq!(&b[12..20], &1.5f64.to_le_bytes());
        assert_eq!(&b[20..24], &3u32.to_le_bytes());
        assert_eq!(&b[24..27], b"ab\0");
        assert_eq!(b[27], 0);
        assert_eq!(&b[28..32], &(-2i32).to_le_bytes());
        let mut r = Reader::new(&b).unwrap();
        assert_eq!(r.u8().unwrap(), 7);
        assert_eq!(r.f64().unwrap(), 1.5);
        assert_eq!(r.string().unwrap(), "ab");
        assert_eq!(r.i32().unwrap(), -2);
        assert!(r.u8().is_err());
    }

    #[test]
    fn a_corrupt_length_is_refused_without_allocating() {
        let mut w = Writer::new();
        w.u32(u32::MAX);
        assert!(Reader::new(&w.finish()).unwrap().bytes().is_err());
        assert!(Reader::new(&[1, 0, 0, 0]).is_err());
        assert!(Reader::new(&[0]).is_err());
    }
}
