//! Writing RGL `tensor_file`s for the tests: a copy of a valid file with some of its fields
//! rewritten (subsampled, repeated along an axis, replaced by one or more), in the container layout of
//! `shared/RGL-FORMAT.md` ("Container").
#![allow(dead_code)]

use diffbsdf_materials::rgl::tensor::{Dtype, Field};
use diffbsdf_materials::rgl::TensorFile;

/// One field to write: name, dtype code, shape, little-endian data.
pub struct Out {
    pub name: String,
    pub dtype: u8,
    pub shape: Vec<usize>,
    pub data: Vec<u8>,
}

/// What a copy does with one field of the original.
pub enum Rewrite {
    /// Keeps it as it is.
    Keep,
    /// Keeps the elements at these indices, one list per axis ([`gather`]).
    Gather(Vec<Vec<usize>>),
    /// Writes another field in its place.
    Replace(Out),
    /// Writes these fields in its place.
    ReplaceMany(Vec<Out>),
}

/// A copy of the valid file `bytes`, each field rewritten as `rewrite` says, in the
/// original's order.
pub fn rewrite(bytes: &[u8], rewrite: impl Fn(&Field<'_>) -> Rewrite) -> Vec<u8> {
    let tf = TensorFile::parse(bytes).unwrap();
    let fields: Vec<Out> = tf
        .fields
        .iter()
        .flat_map(|f| match rewrite(f) {
            Rewrite::Keep => vec![Out {
                name: f.name.clone(),
                dtype: code_of(f),
                shape: f.shape.clone(),
                data: f.bytes.to_vec(),
            }],
            Rewrite::Gather(keep) => vec![Out {
                name: f.name.clone(),
                dtype: code_of(f),
                shape: keep.iter().map(Vec::len).collect(),
                data: gather(f.bytes, &f.shape, &keep, f.bytes.len() / f.len().max(1)),
            }],
            Rewrite::Replace(out) => vec![out],
            Rewrite::ReplaceMany(outs) => outs,
        })
        .collect();
    write_tensor_file(&fields)
}

/// Writes a version 1.0 `tensor_file` with 8-byte aligned data after the header.
pub fn write_tensor_file(fields: &[Out]) -> Vec<u8> {
    let header_len: usize = 18
        + fields
            .iter()
            .map(|f| 2 + f.name.len() + 2 + 1 + 8 + 8 * f.shape.len())
            .sum::<usize>();
    let mut offsets = Vec::new();
    let mut at = header_len.next_multiple_of(8);
    for f in fields {
        offsets.push(at);
        at = (at + f.data.len()).next_multiple_of(8);
    }
    let mut b = Vec::with_capacity(at);
    b.extend_from_slice(b"tensor_file\0");
    b.extend_from_slice(&[1, 0]);
    b.extend_from_slice(&(fields.len() as u32).to_le_bytes());
    for (f, off) in fields.iter().zip(&offsets) {
        b.extend_from_slice(&(f.name.len() as u16).to_le_bytes());
        b.extend_from_slice(f.name.as_bytes());
        b.extend_from_slice(&(f.shape.len() as u16).to_le_bytes());
        b.push(f.dtype);
        b.extend_from_slice(&(*off as u64).to_le_bytes());
        for &s in &f.shape {
            b.extend_from_slice(&(s as u64).to_le_bytes());
        }
    }
    for (f, off) in fields.iter().zip(&offsets) {
        b.resize(*off, 0);
        b.extend_from_slice(&f.data);
    }
    b.resize(at, 0);
    b
}

/// The elements of an n-d array (row-major, `elem` bytes each) at the index lists `keep`
/// (one per axis).
pub fn gather(data: &[u8], shape: &[usize], keep: &[Vec<usize>], elem: usize) -> Vec<u8> {
    let mut out = Vec::new();
    let mut idx = vec![0usize; shape.len()];
    loop {
        let mut flat = 0;
        for (d, &i) in idx.iter().enumerate() {
            flat = flat * shape[d] + keep[d][i];
        }
        out.extend_from_slice(&data[flat * elem..(flat + 1) * elem]);
        let mut d = shape.len();
        loop {
            if d == 0 {
                return out;
            }
            d -= 1;
            idx[d] += 1;
            if idx[d] < keep[d].len() {
                break;
            }
            idx[d] = 0;
        }
    }
}

/// `m` evenly spread indices of `0..n`, first and last included.
pub fn spread(n: usize, m: usize) -> Vec<usize> {
    if n <= m {
        return (0..n).collect();
    }
    (0..m).map(|k| k * (n - 1) / (m - 1)).collect()
}

/// The dtype code of a field (RGL-FORMAT.md, "Container").
pub fn code_of(f: &Field<'_>) -> u8 {
    match f.dtype {
        Dtype::U8 => 1,
        Dtype::I8 => 2,
        Dtype::U16 => 3,
        Dtype::I16 => 4,
        Dtype::U32 => 5,
        Dtype::I32 => 6,
        Dtype::U64 => 7,
        Dtype::I64 => 8,
        Dtype::F16 => 9,
        Dtype::F32 => 10,
        Dtype::F64 => 11,
    }
}
