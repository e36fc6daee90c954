use super::*;
use std::io::Write;

/// One shape's header and zlib stream (version 4 or 3).
fn shape(version: u16, flags: u32, pos: &[f32], nrm: &[f32], uv: &[f32], tris: &[u32]) -> Vec<u8> {
    let mut raw = Vec::new();
    raw.extend_from_slice(&flags.to_le_bytes());
    if version == 4 {
        raw.extend_from_slice(b"quad\0");
    }
    raw.extend_from_slice(&(pos.len() as u64 / 3).to_le_bytes());
    raw.extend_from_slice(&(tris.len() as u64 / 3).to_le_bytes());
    let double = flags & DOUBLE != 0;
    for v in pos.iter().chain(nrm).chain(uv) {
        if double {
            raw.extend_from_slice(&(*v as f64).to_le_bytes());
        } else {
            raw.extend_from_slice(&v.to_le_bytes());
        }
    }
    for i in tris {
        raw.extend_from_slice(&i.to_le_bytes());
    }
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&raw).unwrap();
    let mut out = FORMAT.to_le_bytes().to_vec();
    out.extend_from_slice(&version.to_le_bytes());
    out.extend(z.finish().unwrap());
    out
}

/// Shapes concatenated, with the dictionary of offsets at the end.
fn file(version: u16, shapes: &[Vec<u8>]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for s in shapes {
        offsets.push(out.len() as u64);
        out.extend_from_slice(s);
    }
    for o in offsets {
        if version == 4 {
            out.extend_from_slice(&o.to_le_bytes());
        } else {
            out.extend_from_slice(&(o as u32).to_le_bytes());
        }
    }
    out.extend_from_slice(&(shapes.len() as u32).to_le_bytes());
    out
}

const QUAD: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
const UP: [f32; 12] = [0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.];
const UV: [f32; 8] = [0., 0., 1., 0., 1., 1., 0., 0.25];
const TRIS: [u32; 6] = [0, 1, 2, 0, 2, 3];

#[test]
fn every_shape_of_both_versions_reads_back_as_written() {
    for version in [3, 4] {
        for double in [false, true] {
            let f = if double { DOUBLE } else { 0x1000 };
            let a = shape(
                version,
                f | HAS_NORMALS | HAS_TEXCOORDS,
                &QUAD,
                &UP,
                &UV,
                &TRIS,
            );
            let scaled: Vec<f32> = QUAD.iter().map(|v| v * 2.0).collect();
            let b = shape(version, f, &scaled, &[], &[], &TRIS[..3]);
            let bytes = file(version, &[a, b]);
            let m = parse_serialized(&bytes, 0).unwrap();
            assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
            assert_eq!(m.normals.as_ref().unwrap()[3], Vec3::Z);
            // v as kalos stores it: 1 - v
            assert_eq!(m.uvs.as_ref().unwrap()[3], Vec2::new(0.0, 0.75));
            assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
            let m = parse_serialized(&bytes, 1).unwrap();
            assert_eq!(m.positions[2], Vec3::new(2.0, 2.0, 0.0));
            assert!(m.normals.is_none() && m.uvs.is_none());
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
        }
    }
}

#[test]
fn bad_files_are_one_line_errors() {
    let good = file(4, &[shape(4, HAS_NORMALS, &QUAD, &UP, &[], &TRIS)]);
    let err = |b: &[u8], i: i64| {
        let e = parse_serialized(b, i).unwrap_err();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    assert!(err(&good, 1).contains("out of range"));
    assert!(err(&good, -1).contains("0 or more"));
    assert!(err(&good[..3], 0).contains("truncated"));
    assert!(err(&good[..good.len() / 2], 0).contains("truncated"));
    assert!(err(b"PK\x03\x04rest", 0).contains("not a Mitsuba serialized mesh"));
    // a stream that claims 2^40 vertices: refused before anything is allocated
    let mut lie = shape(4, 0, &QUAD, &[], &[], &TRIS);
    let mut raw = Vec::new();
    flate2::read::ZlibDecoder::new(&lie[4..])
        .read_to_end(&mut raw)
        .unwrap();
    raw[9..17].copy_from_slice(&(1u64 << 40).to_le_bytes());
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&raw).unwrap();
    lie.truncate(4);
    lie.extend(z.finish().unwrap());
    assert!(err(&lie, 0).contains("more than its"), "{}", err(&lie, 0));
    // an index past the vertices
    let bad = shape(4, 0, &QUAD, &[], &[], &[0, 1, 9]);
    assert!(err(&bad, 0).contains("names vertex 9"));
    // a dictionary pointing past the end
    let mut two = file(
        3,
        &[
            shape(3, 0, &QUAD, &[], &[], &TRIS),
            shape(3, 0, &QUAD, &[], &[], &TRIS),
        ],
    );
    let n = two.len();
    two[n - 8..n - 4].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(err(&two, 1).contains("past the end"));
}

/// Mitsuba's own test mesh (when the conformance data is beside the repository) reads as
/// the same quad as its OBJ twin.
#[test]
fn mitsubas_rectangle_matches_its_obj() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let Some(dir) = root
        .ancestors()
        .map(|a| a.join("shared/conformance/mitsuba/tests"))
        .find(|d| d.is_dir())
    else {
        return;
    };
    let m = load_serialized(&dir.join("serialized/rectangle_normals_uv.serialized"), 0).unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles.len(), 2);
    assert!(m.normals.is_some() && m.uvs.is_some());
    let obj = std::fs::read_to_string(dir.join("obj/rectangle_normals_uv.obj")).unwrap();
    for p in &m.positions {
        let found = obj.lines().filter(|l| l.starts_with("v ")).any(|l| {
            let v: Vec<f32> = l[2..]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            (Vec3::new(v[0], v[1], v[2]) - *p).length() < 1e-6
        });
        assert!(found, "{p} is not a vertex of the OBJ");
    }
}
