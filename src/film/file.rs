//! The film file (`.kfilm`): a film with the job that made it and the sample ranges it
//! holds, so that renders split over processes or machines (shards) merge exactly.
//!
//! Layout (little endian): magic `KALOSFILM\n`, version (u32), the job as JSON (u64 length +
//! bytes), the job's identity key as JSON (what must match for two parts to merge), the
//! sample ranges [first, end) (u64 count + pairs), width, height, rejections, per pixel
//! (n, 3 sums, 3 sums of squares), splats (flag, then light paths, batch paths and per
//! pixel sums and batch sums), the end mark `END\n`, and the CRC-64 of every byte before
//! it (`input::CRC64`: any single-bit flip, any burst of up to 64 bits is caught). A file
//! that is truncated, damaged, of another version or of another job is refused with a
//! one-line error, and so is one whose fields cannot be a render's: empty, reversed or
//! overlapping sample ranges, a pixel with more samples than its ranges hold, sums beyond
//! what its samples can add up to, bytes after the checksum. Merging checks that no
//! count or sum overflows.

use super::splat::{SplatFilm, BATCHES};
use super::stats::{PixelStats, TERM_MAX};
use super::{check_resolution, Film, Rejections};
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

/// Version 2: the trailing checksum, and the job key names the scene by content.
pub const FILM_VERSION: u32 = 2;
const MAGIC: &[u8; 10] = b"KALOSFILM\n";
const END: &[u8; 4] = b"END\n";

/// A film with what made it.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmFile {
    /// The render job, as JSON (for people and for re-running).
    pub job: String,
    /// What two parts must share to merge: the job without its sample range and threads.
    pub key: String,
    /// Sample index ranges [first, end) this film holds.
    pub ranges: Vec<(u64, u64)>,
    pub film: Film,
}

/// A writer that hashes what passes through it.
struct W<T: Write>(T, crc::Digest<'static, u64, crc::Table<16>>);
impl<T: Write> W<T> {
    fn b(&mut self, b: &[u8]) -> std::io::Result<()> {
        self.1.update(b);
        self.0.write_all(b)
    }
    fn u32(&mut self, v: u32) -> std::io::Result<()> {
        self.b(&v.to_le_bytes())
    }
    fn u64(&mut self, v: u64) -> std::io::Result<()> {
        self.b(&v.to_le_bytes())
    }
    fn i128(&mut self, v: i128) -> std::io::Result<()> {
        self.b(&v.to_le_bytes())
    }
    fn str(&mut self, s: &str) -> std::io::Result<()> {
        self.u64(s.len() as u64)?;
        self.b(s.as_bytes())
    }
}

/// The film file's bytes, written to any writer.
fn encode<T: Write>(out: T, f: &FilmFile) -> std::io::Result<T> {
    let mut w = W(out, crate::input::CRC64.digest());
    w.b(MAGIC)?;
    w.u32(FILM_VERSION)?;
    w.str(&f.job)?;
    w.str(&f.key)?;
    w.u64(f.ranges.len() as u64)?;
    for &(a, b) in &f.ranges {
        w.u64(a)?;
        w.u64(b)?;
    }
    let film = &f.film;
    w.u32(film.width)?;
    w.u32(film.height)?;
    w.u64(film.rejected.nan)?;
    w.u64(film.rejected.infinite)?;
    for p in &film.pixels {
        w.u32(p.n)?;
        for c in 0..3 {
            w.i128(p.sum[c])?;
        }
        for c in 0..3 {
            w.i128(p.sum_sq[c])?;
        }
    }
    match &film.splats {
        None => w.b(&[0])?,
        Some(s) => {
            w.b(&[1])?;
            w.u64(s.light_paths)?;
            for &b in &s.batch_paths {
                w.u64(b)?;
            }
            for i in 0..s.sum.len() {
                for c in 0..3 {
                    w.i128(s.sum[i][c])?;
                }
                for b in 0..BATCHES {
                    w.u32(s.batch_n[i][b])?;
                    for c in 0..3 {
                        w.i128(s.batch_sum[i][b][c])?;
                        w.i128(s.batch_splat[i][b][c])?;
                    }
                }
            }
        }
    }
    w.b(END)?;
    let W(mut out, digest) = w;
    out.write_all(&digest.finalize().to_le_bytes())?;
    Ok(out)
}

/// Write a film file.
pub fn write_film(path: &Path, f: &FilmFile) -> Result<(), String> {
    let err = |e: std::io::Error| format!("{}: cannot write the film: {e}", path.display());
    let mut file = std::fs::File::create(path).map_err(err)?;
    let mut w = encode(BufWriter::new(&mut file), f).map_err(err)?;
    w.flush().map_err(err)?;
    drop(w);
    file.sync_all().map_err(err)
}

/// A film file's bytes in memory (what `write_film` writes): a shard of a distributed
/// render travels as these, without a shared disk.
pub fn film_to_bytes(f: &FilmFile) -> Vec<u8> {
    let px = f.film.pixels.len();
    let splat = f
        .film
        .splats
        .as_ref()
        .map_or(0, |_| px * (48 + BATCHES * 100));
    let cap = 72 + f.job.len() + f.key.len() + 16 * f.ranges.len() + 100 * px + splat;
    encode(Vec::with_capacity(cap), f).expect("writing to memory cannot fail")
}

/// A reader that hashes what it reads, and counts the bytes left.
struct R<'a, T: Read> {
    r: T,
    name: &'a str,
    left: u64,
    digest: crc::Digest<'static, u64, crc::Table<16>>,
}
impl<'a, T: Read> R<'a, T> {
    fn new(r: T, name: &'a str, left: u64) -> Self {
        R {
            r,
            name,
            left,
            digest: crate::input::CRC64.digest(),
        }
    }
    fn b<const K: usize>(&mut self) -> Result<[u8; K], String> {
        let mut buf = [0u8; K];
        self.r.read_exact(&mut buf).map_err(|_| self.short())?;
        self.digest.update(&buf);
        self.left = self.left.saturating_sub(K as u64);
        Ok(buf)
    }
    fn short(&self) -> String {
        format!(
            "{}: the film file is truncated (or not a kalos film)",
            self.name
        )
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.b()?))
    }
    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.b()?))
    }
    fn i128(&mut self) -> Result<i128, String> {
        Ok(i128::from_le_bytes(self.b()?))
    }
    fn str(&mut self) -> Result<String, String> {
        let n = self.u64()?;
        if n > self.left {
            return Err(self.short());
        }
        let mut v = vec![0u8; n as usize];
        self.r.read_exact(&mut v).map_err(|_| self.short())?;
        self.digest.update(&v);
        self.left -= n;
        String::from_utf8(v).map_err(|_| format!("{}: the film's job is not UTF-8", self.name))
    }
}

/// Read a film file, checking its magic, version and size before allocating.
pub fn read_film(path: &Path) -> Result<FilmFile, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if !meta.is_file() {
        return Err(format!("{}: not a regular file", path.display()));
    }
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let name = path.display().to_string();
    decode(R::new(BufReader::new(file), &name, meta.len()))
}

/// A film file from its bytes (`film_to_bytes`), checked as `read_film` checks a file.
/// `name` starts the error messages.
pub fn film_from_bytes(bytes: &[u8], name: &str) -> Result<FilmFile, String> {
    decode(R::new(bytes, name, bytes.len() as u64))
}

/// The film, its checksum and its fields checked; nothing may follow the checksum.
fn decode<T: Read>(mut r: R<'_, T>) -> Result<FilmFile, String> {
    let name = r.name;
    let magic: [u8; 10] = r
        .b()
        .map_err(|_| format!("{name}: not a kalos film file"))?;
    if &magic != MAGIC {
        return Err(format!("{name}: not a kalos film file"));
    }
    let version = r.u32()?;
    if version != FILM_VERSION {
        return Err(format!(
            "{name}: film file version {version}, this kalos reads version {FILM_VERSION}: render the part again with this kalos"
        ));
    }
    let job = r.str()?;
    let key = r.str()?;
    let nr = r.u64()?;
    if nr > r.left / 16 {
        return Err(r.short());
    }
    let mut ranges = Vec::with_capacity(nr as usize);
    for _ in 0..nr {
        let a = r.u64()?;
        let b = r.u64()?;
        ranges.push((a, b));
    }
    let width = r.u32()?;
    let height = r.u32()?;
    let pixels = width as u64 * height as u64;
    // 100 bytes per pixel must still be in the file.
    if pixels.saturating_mul(100) > r.left {
        return Err(r.short());
    }
    check_resolution(width, height).map_err(|e| format!("{name}: {e}"))?;
    let mut film = Film::new(width, height)?;
    film.rejected = Rejections {
        nan: r.u64()?,
        infinite: r.u64()?,
    };
    for p in film.pixels.iter_mut() {
        let n = r.u32()?;
        let mut q = PixelStats {
            n,
            ..Default::default()
        };
        for c in 0..3 {
            q.sum[c] = r.i128()?;
        }
        for c in 0..3 {
            q.sum_sq[c] = r.i128()?;
        }
        *p = q;
    }
    let [flag] = r.b::<1>()?;
    if flag == 1 {
        if pixels.saturating_mul(48 + BATCHES as u64 * 100) > r.left {
            return Err(r.short());
        }
        let mut s = SplatFilm::new(pixels as usize);
        s.light_paths = r.u64()?;
        for b in 0..BATCHES {
            s.batch_paths[b] = r.u64()?;
        }
        for i in 0..pixels as usize {
            for c in 0..3 {
                s.sum[i][c] = r.i128()?;
            }
            for b in 0..BATCHES {
                s.batch_n[i][b] = r.u32()?;
                for c in 0..3 {
                    s.batch_sum[i][b][c] = r.i128()?;
                    s.batch_splat[i][b][c] = r.i128()?;
                }
            }
        }
        film.splats = Some(Box::new(s));
    } else if flag != 0 {
        return Err(format!("{name}: damaged film file (splat flag {flag})"));
    }
    let end: [u8; 4] = r.b()?;
    if &end != END {
        return Err(r.short());
    }
    let computed = std::mem::replace(&mut r.digest, crate::input::CRC64.digest()).finalize();
    let stored = u64::from_le_bytes(r.b()?);
    if stored != computed {
        return Err(format!(
            "{name}: damaged film file (its checksum does not match its contents)"
        ));
    }
    if r.left != 0 {
        return Err(format!(
            "{name}: {} bytes after the film's checksum (not one kalos film)",
            r.left
        ));
    }
    let f = FilmFile {
        job,
        key,
        ranges,
        film,
    };
    check_fields(&f).map_err(|e| format!("{name}: damaged film file ({e})"))?;
    Ok(f)
}

/// What a render's film always satisfies: non-empty, increasing, disjoint sample
/// ranges; no pixel with more samples than they hold; sums no larger than that many
/// samples add up to (each at most `TERM_MAX` in fixed point), sums of squares not
/// negative; splat batches that count the pixel's samples.
fn check_fields(f: &FilmFile) -> Result<(), String> {
    let held = check_ranges(&f.ranges)?;
    let film = &f.film;
    let term = TERM_MAX as i128;
    for (i, p) in film.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % film.width, i as u32 / film.width);
        if p.n as u64 > held {
            return Err(format!(
                "pixel ({x}, {y}) has {} samples, its sample ranges hold {held}",
                p.n
            ));
        }
        let most = p.n as i128 * term;
        let bad = (0..3).any(|c| p.sum[c].abs() > most || p.sum_sq[c] < 0 || p.sum_sq[c] > most);
        if bad {
            return Err(format!(
                "pixel ({x}, {y}): sums beyond what {} samples add up to",
                p.n
            ));
        }
        if let Some(s) = &film.splats {
            if s.batch_n[i].iter().map(|&k| k as u64).sum::<u64>() != p.n as u64 {
                return Err(format!(
                    "pixel ({x}, {y}): its splat batches count other samples than the pixel"
                ));
            }
        }
    }
    Ok(())
}

/// Ranges [first, end) that a render can have given: at least one, none empty or
/// reversed, none overlapping another. Returns how many sample indices they hold.
fn check_ranges(ranges: &[(u64, u64)]) -> Result<u64, String> {
    if ranges.is_empty() {
        return Err("no sample range".into());
    }
    let mut sorted = ranges.to_vec();
    sorted.sort_unstable();
    let mut held = 0u64;
    for (k, &(a, b)) in sorted.iter().enumerate() {
        if a >= b {
            return Err(format!("sample range {a}..{b} is empty or reversed"));
        }
        if let Some(&(c, d)) = sorted.get(k + 1).filter(|&&(c, _)| c < b) {
            return Err(format!("sample ranges {a}..{b} and {c}..{d} overlap"));
        }
        held = held.saturating_add(b - a);
    }
    Ok(held)
}

/// Whether `b`'s counts and sums can be added to `a`'s without overflow.
fn can_merge(a: &super::Film, b: &super::Film) -> bool {
    let px = a.pixels.iter().zip(&b.pixels).all(|(p, q)| {
        p.n.checked_add(q.n).is_some()
            && (0..3).all(|c| {
                p.sum[c].checked_add(q.sum[c]).is_some()
                    && p.sum_sq[c].checked_add(q.sum_sq[c]).is_some()
            })
    });
    let rej = a.rejected.nan.checked_add(b.rejected.nan).is_some()
        && a.rejected
            .infinite
            .checked_add(b.rejected.infinite)
            .is_some();
    let splats = match (&a.splats, &b.splats) {
        (Some(s), Some(t)) => {
            let add3 =
                |u: &[i128; 3], v: &[i128; 3]| (0..3).all(|c| u[c].checked_add(v[c]).is_some());
            s.light_paths.checked_add(t.light_paths).is_some()
                && (0..BATCHES).all(|k| s.batch_paths[k].checked_add(t.batch_paths[k]).is_some())
                && (0..s.sum.len()).all(|i| {
                    add3(&s.sum[i], &t.sum[i])
                        && (0..BATCHES).all(|k| {
                            s.batch_n[i][k].checked_add(t.batch_n[i][k]).is_some()
                                && add3(&s.batch_sum[i][k], &t.batch_sum[i][k])
                                && add3(&s.batch_splat[i][k], &t.batch_splat[i][k])
                        })
                })
        }
        _ => true,
    };
    px && rej && splats
}

/// Merge film files: the same job key, the same size, disjoint sample ranges. The result
/// is exact and independent of the order of the parts.
pub fn merge_files(parts: &[(String, FilmFile)]) -> Result<FilmFile, String> {
    let Some((first_name, first)) = parts.first() else {
        return Err("merge: no film files given".into());
    };
    check_ranges(&first.ranges).map_err(|e| format!("{first_name}: {e}"))?;
    let mut out = first.clone();
    for (name, p) in &parts[1..] {
        check_ranges(&p.ranges).map_err(|e| format!("{name}: {e}"))?;
        if p.key != out.key {
            return Err(format!(
                "{name}: a part of another render than {first_name} (scene, options or seed differ)"
            ));
        }
        if (p.film.width, p.film.height) != (out.film.width, out.film.height) {
            return Err(format!(
                "{name}: {}x{} pixels, {first_name} has {}x{}",
                p.film.width, p.film.height, out.film.width, out.film.height
            ));
        }
        for &(a, b) in &p.ranges {
            if let Some(&(c, d)) = out.ranges.iter().find(|&&(c, d)| a < d && c < b) {
                return Err(format!(
                    "{name}: samples {a}..{b} overlap samples {c}..{d} of another part"
                ));
            }
        }
        if !can_merge(&out.film, &p.film) {
            return Err(format!(
                "{name}: merged with the parts before it, a pixel's sample count or sums would overflow"
            ));
        }
        out.ranges.extend_from_slice(&p.ranges);
        out.film.merge(&p.film);
    }
    out.ranges.sort_unstable();
    Ok(out)
}
