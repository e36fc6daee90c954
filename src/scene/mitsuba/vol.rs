//! Mitsuba's grid volume files (`.vol`): the bytes `VOL` and version 3, then little-endian
//! the encoding (`i32`, 1: single-precision floats, the one Mitsuba 3 reads), the sample
//! counts along x, y and z and the channels per sample (`i32` each), the bounding box
//! (six `f32`: min x y z, max x y z), then the samples, x fastest, the channels of a
//! sample together. The size the header gives is checked against the file's length
//! before anything is allocated.

use std::path::Path;

/// Bytes before the samples.
const HEADER: usize = 48;

/// A grid volume: samples per axis, channels, the bounding box and the data.
#[derive(Clone, Debug, PartialEq)]
pub struct VolGrid {
    pub res: [u32; 3],
    pub channels: u32,
    pub bbox: [f32; 6],
    pub data: Vec<f32>,
}

/// The grid volume at `path`; errors name the file and what is wrong.
pub fn load_vol(path: &Path) -> Result<VolGrid, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    parse_vol(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(b[at..at + 4].try_into().expect("four bytes"))
}

/// A grid volume from its bytes.
pub fn parse_vol(b: &[u8]) -> Result<VolGrid, String> {
    if b.len() < 4 || &b[..3] != b"VOL" {
        return Err("not a Mitsuba grid volume (it does not start with 'VOL')".into());
    }
    if b[3] != 3 {
        return Err(format!(
            "grid volume version {}: kalos reads version 3",
            b[3]
        ));
    }
    if b.len() < HEADER {
        return Err(format!(
            "truncated: {} bytes, shorter than the {HEADER}-byte header",
            b.len()
        ));
    }
    let encoding = i32_at(b, 4);
    if encoding != 1 {
        return Err(format!(
            "grid volume encoding {encoding}: kalos reads 1 (single-precision floats), as Mitsuba 3"
        ));
    }
    let dims = [8, 12, 16, 20].map(|at| i32_at(b, at));
    if dims.iter().any(|&n| n <= 0) {
        return Err(format!(
            "{} x {} x {} samples of {} channels: each must be positive",
            dims[0], dims[1], dims[2], dims[3]
        ));
    }
    let count = dims.iter().map(|&n| n as u64).product::<u64>();
    let need = count
        .checked_mul(4)
        .and_then(|n| n.checked_add(HEADER as u64));
    if need != Some(b.len() as u64) {
        let need = need.map_or("more than 2^64".to_string(), |n| n.to_string());
        return Err(format!(
            "{} bytes, but its header ({} x {} x {} samples of {} channels) needs {need}",
            b.len(),
            dims[0],
            dims[1],
            dims[2],
            dims[3]
        ));
    }
    let f32s = |from: usize| {
        b[from..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("four bytes")))
    };
    let mut bbox = [0.0; 6];
    for (o, v) in bbox.iter_mut().zip(f32s(24)) {
        *o = v;
    }
    Ok(VolGrid {
        res: [dims[0] as u32, dims[1] as u32, dims[2] as u32],
        channels: dims[3] as u32,
        bbox,
        data: f32s(HEADER).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of `res` samples of one channel whose values are their indices.
    pub(crate) fn vol_bytes(res: [i32; 3]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, res[0], res[1], res[2], 1] {
            b.extend_from_slice(&i32::to_le_bytes(v));
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for i in 0..res.iter().product::<i32>() {
            b.extend_from_slice(&(i as f32).to_le_bytes());
        }
        b
    }

    #[test]
    fn reads_a_grid_volume() {
        let g = parse_vol(&vol_bytes([3, 2, 2])).unwrap();
        assert_eq!(g.res, [3, 2, 2]);
        assert_eq!(g.channels, 1);
        assert_eq!(g.bbox, [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        assert_eq!(g.data, (0..12).map(|i| i as f32).collect::<Vec<_>>());
    }

    #[test]
    fn bad_files_are_one_line_naming_what_is_wrong() {
        let good = vol_bytes([3, 2, 2]);
        let err = |b: &[u8]| parse_vol(b).unwrap_err();
        assert!(err(b"PLY").contains("does not start with 'VOL'"));
        assert!(err(b"VOL\x02").contains("version 2"));
        assert!(err(&good[..30]).contains("header"));
        let e = err(&good[..good.len() - 1]);
        assert!(e.contains("95 bytes") && e.contains("needs 96"), "{e}");
        let mut b = good.clone();
        b[4] = 3;
        assert!(err(&b).contains("encoding 3"));
        // a header that lies about its size is refused before anything is allocated
        let mut b = good.clone();
        b[8..12].copy_from_slice(&i32::MAX.to_le_bytes());
        b[12..16].copy_from_slice(&i32::MAX.to_le_bytes());
        let e = err(&b);
        assert!(e.contains("2147483647 x 2147483647 x 2 samples"), "{e}");
        let mut b = good;
        b[16..20].copy_from_slice(&(-2i32).to_le_bytes());
        assert!(err(&b).contains("must be positive"));
        for e in [err(b""), err(&b[..47])] {
            assert!(!e.contains('\n'), "{e}");
        }
    }
}
