//! The tensor files of the RGL material database (`.bsdf`): named,
//! typed n-dimensional arrays, as Mitsuba and pbrt-v4 read them.
//!
//! Little endian: the 12 bytes `tensor_file\0`, a version (1, 0), a u32
//! field count, then per field its name (u16 length, bytes), rank (u16),
//! type (u8), the u64 offset of its data in the file and a u64 size per
//! dimension. The data is in C order.

use std::collections::HashMap;

/// Type codes (Mitsuba's `Struct::Type`).
const UINT8: u8 = 1;
const FLOAT32: u8 = 10;
const FLOAT64: u8 = 11;

/// Bytes an element of type `t` takes; `None` for an unknown type.
fn type_size(t: u8) -> Option<usize> {
    Some(match t {
        1 | 2 => 1,
        3 | 4 | 9 => 2,
        5 | 6 | 10 => 4,
        7 | 8 | 11 => 8,
        _ => return None,
    })
}

/// One field: its type, shape and bytes.
#[derive(Clone, Debug)]
pub struct Field<'a> {
    pub dtype: u8,
    pub shape: Vec<usize>,
    bytes: &'a [u8],
}

impl Field<'_> {
    /// The values as f32 (from 32- or 64-bit floats), or why not.
    pub fn floats(&self) -> Result<Vec<f32>, String> {
        match self.dtype {
            FLOAT32 => Ok(self
                .bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect()),
            FLOAT64 => Ok(self
                .bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as f32)
                .collect()),
            t => Err(format!("holds type {t}, not floats")),
        }
    }

    pub fn is_bytes(&self) -> bool {
        self.dtype == UINT8
    }

    pub fn bytes(&self) -> &[u8] {
        self.bytes
    }
}

/// A tensor file's fields by name, borrowing the file's bytes.
#[derive(Debug)]
pub struct TensorFile<'a> {
    fields: HashMap<String, Field<'a>>,
}

impl<'a> TensorFile<'a> {
    /// Reads the header and checks that every field lies within the file.
    pub fn parse(file: &'a [u8]) -> Result<Self, String> {
        let mut at = 0usize;
        let mut take = |n: usize| -> Result<&'a [u8], String> {
            let end = at
                .checked_add(n)
                .filter(|&e| e <= file.len())
                .ok_or("the file ends inside its header")?;
            let s = &file[at..end];
            at = end;
            Ok(s)
        };
        if take(12)? != b"tensor_file\0" {
            return Err("not a tensor file (no \"tensor_file\" header)".into());
        }
        let version = take(2)?;
        if version != [1, 0] {
            return Err(format!("tensor file version {}.{}, not 1.0", version[0], version[1]));
        }
        let u16_ = |b: &[u8]| u16::from_le_bytes([b[0], b[1]]) as usize;
        let u64_ = |b: &[u8]| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]);
        let b = take(4)?;
        let count = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize;
        let mut fields = HashMap::new();
        for _ in 0..count {
            let len = u16_(take(2)?);
            let name = String::from_utf8_lossy(take(len)?).into_owned();
            let rank = u16_(take(2)?);
            let dtype = take(1)?[0];
            let offset = u64_(take(8)?);
            let size = type_size(dtype).ok_or_else(|| format!("field \"{name}\": unknown type {dtype}"))?;
            let mut shape = Vec::with_capacity(rank.min(16));
            let mut bytes = size as u64;
            for _ in 0..rank {
                let n = u64_(take(8)?);
                shape.push(usize::try_from(n).map_err(|_| format!("field \"{name}\": size {n} is too large"))?);
                bytes = bytes.saturating_mul(n);
            }
            let end = offset.saturating_add(bytes);
            if end > file.len() as u64 {
                return Err(format!(
                    "field \"{name}\" runs to byte {end}, past the file's end ({} bytes)",
                    file.len()
                ));
            }
            let data = &file[offset as usize..end as usize];
            fields.insert(
                name,
                Field {
                    dtype,
                    shape,
                    bytes: data,
                },
            );
        }
        Ok(TensorFile { fields })
    }

    /// The field of this name, or an error naming it.
    pub fn field(&self, name: &str) -> Result<&Field<'a>, String> {
        self.fields.get(name).ok_or_else(|| format!("no field \"{name}\""))
    }
}

/// Writes a tensor file (for tests and tools): fields of f32 or u8.
#[cfg(test)]
pub fn write(fields: &[(&str, Vec<usize>, TestData)]) -> Vec<u8> {
    let mut head = Vec::new();
    head.extend_from_slice(b"tensor_file\0");
    head.extend_from_slice(&[1, 0]);
    head.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    let header_len: usize = head.len()
        + fields
            .iter()
            .map(|(n, s, _)| 2 + n.len() + 2 + 1 + 8 + 8 * s.len())
            .sum::<usize>();
    let mut body = Vec::new();
    for (name, shape, data) in fields {
        head.extend_from_slice(&(name.len() as u16).to_le_bytes());
        head.extend_from_slice(name.as_bytes());
        head.extend_from_slice(&(shape.len() as u16).to_le_bytes());
        let (dtype, bytes): (u8, Vec<u8>) = match data {
            TestData::F32(v) => (FLOAT32, v.iter().flat_map(|x| x.to_le_bytes()).collect()),
            TestData::U8(v) => (UINT8, v.clone()),
        };
        head.push(dtype);
        head.extend_from_slice(&((header_len + body.len()) as u64).to_le_bytes());
        for &n in shape {
            head.extend_from_slice(&(n as u64).to_le_bytes());
        }
        body.extend_from_slice(&bytes);
    }
    head.extend_from_slice(&body);
    head
}

#[cfg(test)]
pub enum TestData {
    F32(Vec<f32>),
    U8(Vec<u8>),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_read_back_as_written_and_bad_files_are_refused() {
        let file = write(&[
            ("a", vec![2, 3], TestData::F32((0..6).map(|i| i as f32 * 0.5).collect())),
            ("note", vec![3], TestData::U8(b"abc".to_vec())),
        ]);
        let t = TensorFile::parse(&file).unwrap();
        let a = t.field("a").unwrap();
        assert_eq!(a.shape, vec![2, 3]);
        assert_eq!(a.floats().unwrap(), vec![0.0, 0.5, 1.0, 1.5, 2.0, 2.5]);
        let note = t.field("note").unwrap();
        assert!(note.is_bytes() && note.bytes() == b"abc");
        assert!(note.floats().is_err());
        assert!(t.field("b").unwrap_err().contains("\"b\""));
        // Truncated anywhere: an error, never a panic.
        for cut in 0..file.len() {
            let r = TensorFile::parse(&file[..cut]);
            assert!(r.is_err(), "cut at {cut}");
        }
        let mut bad = file.clone();
        bad[0] = b'x';
        assert!(TensorFile::parse(&bad).unwrap_err().contains("header"));
    }
}
