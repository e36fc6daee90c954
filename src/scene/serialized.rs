//! Mitsuba's `.serialized` meshes: per shape a little-endian header (format 0x041C,
//! version 3 or 4) and a zlib stream (flags, in version 4 the shape's name, vertex and
//! triangle counts, positions, then normals, texture coordinates and colours as the flags
//! say, in single or double precision, then `u32` indices); a file of several shapes ends
//! with the offset of each (`u64`, `u32` in version 3) and their count (`u32`).
//!
//! Sizes are checked against what the file can hold before anything is allocated: a
//! deflate stream expands at most 1032 times, so counts that would need more bytes than
//! that are refused, as are a stream that ends early and indices out of range.

use super::ply::PlyMesh;
use crate::math::{Vec2, Vec3};
use std::io::Read;
use std::path::Path;

const FORMAT: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE: u32 = 0x2000;
/// Deflate's largest expansion (a 258-byte match per 2 bits), rounded up.
const MAX_RATIO: u64 = 1032;

/// Shape `shape_index` of the `.serialized` file at `path` (texture coordinates in kalos'
/// convention: Mitsuba reads this format's v as written, which is kalos' 1 - v).
pub fn load_serialized(path: &Path, shape_index: i64) -> Result<PlyMesh, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    parse_serialized(&bytes, shape_index).map_err(|e| format!("{}: {e}", path.display()))
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// The header at `at`: the version, checked.
fn header(b: &[u8], at: usize) -> Result<u16, String> {
    let (Some(format), Some(version)) = (u16_at(b, at), u16_at(b, at + 2)) else {
        return Err(format!("truncated: no shape header at byte {at}"));
    };
    if format != FORMAT {
        return Err(format!(
            "not a Mitsuba serialized mesh (header {format:#06x} at byte {at}, expected {FORMAT:#06x})"
        ));
    }
    if version != 3 && version != 4 {
        return Err(format!(
            "serialized version {version}: kalos reads versions 3 and 4"
        ));
    }
    Ok(version)
}

/// Where shape `index` starts (its header), from the dictionary at the end of the file.
fn shape_offset(b: &[u8], index: i64, version: u16) -> Result<usize, String> {
    if index < 0 {
        return Err(format!("shape_index {index}: must be 0 or more"));
    }
    if index == 0 {
        return Ok(0);
    }
    let n = b.len();
    let count = n
        .checked_sub(4)
        .and_then(|at| u32_at(b, at))
        .ok_or("truncated: no shape count at the end")? as u64;
    if index as u64 >= count {
        return Err(format!(
            "shape_index {index} is out of range: the file holds {count} shape(s)"
        ));
    }
    let k = count - index as u64;
    let offset = if version == 4 {
        (n as u64)
            .checked_sub(8 * k + 4)
            .and_then(|at| u64_at(b, at as usize))
    } else {
        (n as u64)
            .checked_sub(4 * (k + 1))
            .and_then(|at| u32_at(b, at as usize).map(u64::from))
    }
    .ok_or_else(|| format!("truncated: the shape dictionary ({count} shapes) does not fit"))?;
    if offset + 4 > n as u64 {
        return Err(format!(
            "shape {index} starts at byte {offset}, past the end ({n} bytes)"
        ));
    }
    Ok(offset as usize)
}

/// Parses shape `shape_index` of a `.serialized` file's bytes.
pub fn parse_serialized(b: &[u8], shape_index: i64) -> Result<PlyMesh, String> {
    let version = header(b, 0)?;
    let at = shape_offset(b, shape_index, version)?;
    let version = header(b, at)?;
    let cap = (b.len() as u64).saturating_mul(MAX_RATIO);
    let mut z = flate2::read::ZlibDecoder::new(&b[at + 4..]);
    let bad = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => {
            format!("shape {shape_index}: truncated (the compressed data ends early)")
        }
        _ => format!("shape {shape_index}: corrupt compressed data ({e})"),
    };
    let mut word = [0u8; 8];
    let mut flags = [0u8; 4];
    z.read_exact(&mut flags).map_err(bad)?;
    let flags = u32::from_le_bytes(flags);
    if version == 4 {
        // the shape's name, NUL-terminated
        let mut ch = [0u8; 1];
        for _ in 0..=65536 {
            z.read_exact(&mut ch).map_err(bad)?;
            if ch[0] == 0 {
                break;
            }
        }
        if ch[0] != 0 {
            return Err(format!("shape {shape_index}: its name does not end"));
        }
    }
    z.read_exact(&mut word).map_err(bad)?;
    let nv = u64::from_le_bytes(word);
    z.read_exact(&mut word).map_err(bad)?;
    let nf = u64::from_le_bytes(word);
    let fsize: u64 = if flags & DOUBLE != 0 { 8 } else { 4 };
    let has = |f: u32| flags & f != 0;
    let per_vertex = 3
        + 3 * has(HAS_NORMALS) as u64
        + 2 * has(HAS_TEXCOORDS) as u64
        + 3 * has(HAS_COLORS) as u64;
    let need = nv
        .checked_mul(per_vertex * fsize)
        .and_then(|v| nf.checked_mul(12).and_then(|f| v.checked_add(f)));
    match need {
        Some(need) if need <= cap && nv <= u32::MAX as u64 => {}
        _ => {
            return Err(format!(
                "shape {shape_index} claims {nv} vertices and {nf} triangles: more than its {} bytes can hold",
                b.len()
            ))
        }
    }
    let mut floats = |dim: usize| -> Result<Vec<f32>, String> {
        let n = nv as usize * dim;
        let mut raw = vec![0u8; n * fsize as usize];
        z.read_exact(&mut raw).map_err(bad)?;
        Ok(if fsize == 8 {
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()) as f32)
                .collect()
        } else {
            raw.chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                .collect()
        })
    };
    let v3 = |v: Vec<f32>| -> Vec<Vec3> { v.chunks_exact(3).map(Vec3::from_slice).collect() };
    let positions = v3(floats(3)?);
    let normals = if has(HAS_NORMALS) {
        Some(v3(floats(3)?))
    } else {
        None
    };
    let uvs = if has(HAS_TEXCOORDS) {
        let t = floats(2)?;
        Some(
            t.chunks_exact(2)
                .map(|c| Vec2::new(c[0], 1.0 - c[1]))
                .collect(),
        )
    } else {
        None
    };
    if has(HAS_COLORS) {
        floats(3)?;
    }
    let mut raw = vec![0u8; nf as usize * 12];
    z.read_exact(&mut raw).map_err(bad)?;
    let mut triangles = Vec::with_capacity(nf as usize);
    for (i, c) in raw.chunks_exact(12).enumerate() {
        let t = [0, 1, 2].map(|k| u32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()));
        if let Some(bad) = t.iter().find(|&&v| v as u64 >= nv) {
            return Err(format!(
                "shape {shape_index}: triangle {i} names vertex {bad}, but there are {nv}"
            ));
        }
        triangles.push(t);
    }
    Ok(PlyMesh {
        positions,
        normals,
        uvs,
        triangles,
        attributes: Vec::new(),
    })
}

#[cfg(test)]
#[path = "serialized_tests.rs"]
mod tests;
