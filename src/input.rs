//! Every file kalos reads (scenes, OBJ, MTL, TOML, textures, images, experiment files)
//! goes through [`read_bytes`]: only regular files are read, and no more than a stated
//! limit, so no input can make kalos block for ever (a FIFO), read for ever (`/dev/zero`)
//! or take the machine's memory. A file that is not a regular file is named for what it
//! is (directory, FIFO, character device, ...). Text is normalised by [`clean_text`]: a
//! UTF-8 byte-order mark is dropped and old-Mac CR-only line ends become line ends.

use std::borrow::Cow;
use std::cell::RefCell;
use std::io::Read;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// The default limit on the size of one input file: 4 GiB. Larger inputs are refused
/// before they are read. The environment variable `KALOS_MAX_INPUT_BYTES` (bytes, or with
/// a K/M/G suffix, powers of 1024) or [`set_max_input_bytes`] changes it.
pub const DEFAULT_MAX_INPUT_BYTES: u64 = 4 << 30;

/// The environment variable that overrides [`DEFAULT_MAX_INPUT_BYTES`].
pub const MAX_INPUT_ENV: &str = "KALOS_MAX_INPUT_BYTES";

/// 0: not set (the environment variable or the default applies).
static MAX_INPUT_BYTES: AtomicU64 = AtomicU64::new(0);

/// Set the input size limit for the rest of the process (a command-line option's hook).
pub fn set_max_input_bytes(n: u64) {
    MAX_INPUT_BYTES.store(n.max(1), Ordering::Relaxed);
}

/// Parse a size: bytes, or a number with a K, M or G suffix (powers of 1024).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mult) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m: u64 = match c.to_ascii_uppercase() {
                'K' => 1 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                _ => {
                    return Err(format!(
                        "{s:?}: not a size (bytes, or a number with K, M or G)"
                    ))
                }
            };
            (&t[..i], m)
        }
        _ => (t, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("{s:?}: not a size (bytes, or a number with K, M or G)"))?;
    if !(v.is_finite() && v >= 1.0) {
        return Err(format!("{s:?}: a size must be at least 1 byte"));
    }
    Ok((v * mult as f64).min(u64::MAX as f64) as u64)
}

/// The limit in force: [`set_max_input_bytes`], else `KALOS_MAX_INPUT_BYTES`, else
/// [`DEFAULT_MAX_INPUT_BYTES`]. A malformed variable is an error naming it.
pub fn max_input_bytes() -> Result<u64, String> {
    match MAX_INPUT_BYTES.load(Ordering::Relaxed) {
        0 => match std::env::var(MAX_INPUT_ENV) {
            Ok(v) => parse_size(&v).map_err(|e| format!("{MAX_INPUT_ENV}: {e}")),
            Err(_) => Ok(DEFAULT_MAX_INPUT_BYTES),
        },
        n => Ok(n),
    }
}

/// A size for messages: "3.2 GiB", "512 KiB", "17 bytes".
pub fn human_size(n: u64) -> String {
    let units = [(1u64 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")];
    for (u, name) in units {
        if n >= u {
            let v = n as f64 / u as f64;
            return if v.fract() == 0.0 {
                format!("{v:.0} {name}")
            } else {
                format!("{v:.1} {name}")
            };
        }
    }
    format!("{n} bytes")
}

/// What a path is, when it is not a regular file ("a directory", "a FIFO (named
/// pipe)", ...); None for a regular file.
fn what_it_is(meta: &std::fs::Metadata) -> Option<&'static str> {
    let t = meta.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("a FIFO (named pipe)");
        }
        if t.is_char_device() {
            return Some("a character device");
        }
        if t.is_block_device() {
            return Some("a block device");
        }
        if t.is_socket() {
            return Some("a socket");
        }
    }
    Some("not a regular file")
}

/// Check that `path` is a regular file (following symbolic links) no larger than
/// `limit`; returns its size. Errors name the path and what it is instead.
pub fn check_regular_file(path: &Path, limit: u64) -> Result<u64, String> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, &e))?;
    if let Some(what) = what_it_is(&meta) {
        return Err(format!(
            "{}: is {what}, not a regular file: kalos reads only regular files",
            path.display()
        ));
    }
    if meta.len() > limit {
        return Err(too_large(path, meta.len(), limit));
    }
    Ok(meta.len())
}

fn too_large(path: &Path, len: u64, limit: u64) -> String {
    format!(
        "{}: {} is more than the input limit of {} (set {MAX_INPUT_ENV} to raise it)",
        path.display(),
        human_size(len),
        human_size(limit)
    )
}

fn io_error(path: &Path, e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::NotFound => format!("{}: no such file", path.display()),
        std::io::ErrorKind::PermissionDenied => {
            format!("{}: permission denied", path.display())
        }
        _ => format!("{}: {e}", path.display()),
    }
}

/// Read a whole regular file of at most `limit` bytes.
pub fn read_bytes_limited(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let len = check_regular_file(path, limit)?;
    let file = std::fs::File::open(path).map_err(|e| io_error(path, &e))?;
    // the path may have been replaced between the check and the open: check the handle
    let meta = file.metadata().map_err(|e| io_error(path, &e))?;
    if let Some(what) = what_it_is(&meta) {
        return Err(format!(
            "{}: is {what}, not a regular file: kalos reads only regular files",
            path.display()
        ));
    }
    // a file may grow while it is read (or report a size of 0, as /proc does): read at
    // most limit + 1 bytes, whatever the size said
    let mut buf = Vec::with_capacity(len.min(limit) as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut buf)
        .map_err(|e| io_error(path, &e))?;
    if buf.len() as u64 > limit {
        return Err(too_large(path, buf.len() as u64, limit));
    }
    Ok(buf)
}

/// Read a whole regular file within the input limit ([`max_input_bytes`]). Every file
/// kalos reads goes through here.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, String> {
    let bytes = read_bytes_limited(path, max_input_bytes()?)?;
    RECORDED.with(|r| {
        if let Some(d) = r.borrow_mut().as_mut() {
            d.update(&(bytes.len() as u64).to_le_bytes());
            d.update(&CRC64.checksum(&bytes).to_le_bytes());
        }
    });
    Ok(bytes)
}

/// CRC-64 (ECMA-182, as xz uses it): detects every error of up to 64 consecutive bits,
/// so every single-bit flip; kalos's checksum of film files and of the inputs a render
/// read.
pub static CRC64: crc::Crc<u64, crc::Table<16>> =
    crc::Crc::<u64, crc::Table<16>>::new(&crc::CRC_64_XZ);

thread_local! {
    /// While [`content_hash_of_reads`] runs: the hash of the files read so far.
    static RECORDED: RefCell<Option<crc::Digest<'static, u64, crc::Table<16>>>> =
        const { RefCell::new(None) };
}

/// Run `f` and hash the contents of every file it reads through [`read_bytes`] on this
/// thread, in order (sizes and CRC-64s): two loads that read the same bytes from
/// whatever paths give the same hash. None if `f` read no file.
pub fn content_hash_of_reads<T>(f: impl FnOnce() -> T) -> (T, Option<u64>) {
    let outer = RECORDED.with(|r| r.borrow_mut().replace(CRC64.digest()));
    let out = f();
    let d = RECORDED.with(|r| std::mem::replace(&mut *r.borrow_mut(), outer));
    let empty = CRC64.digest().finalize();
    let h = d.map(|d| d.finalize()).filter(|&h| h != empty);
    (out, h)
}

/// Read a text file as UTF-8 (invalid bytes replaced, as OBJ and MTL files from old tools
/// use Latin-1 names), normalised by [`clean_text`].
pub fn read_text_lossy(path: &Path) -> Result<String, String> {
    let bytes = read_bytes(path)?;
    Ok(clean_text(&String::from_utf8_lossy(&bytes)).into_owned())
}

/// Read a text file that must be UTF-8 (TOML), normalised by [`clean_text`].
pub fn read_text(path: &Path) -> Result<String, String> {
    let bytes = read_bytes(path)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        format!(
            "{}: not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })?;
    Ok(clean_text(&text).into_owned())
}

/// Drop a leading UTF-8 byte-order mark (Blender and Windows tools write one) and turn
/// CR-only line ends (old Mac files) into LF; CRLF stays one line end. Line numbers are
/// kept: each CR, LF or CRLF ends exactly one line.
pub fn clean_text(text: &str) -> Cow<'_, str> {
    let t = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !t.contains('\r') {
        return Cow::Borrowed(t);
    }
    let mut out = String::with_capacity(t.len());
    let mut chars = t.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\r' {
            if chars.peek() != Some(&'\n') {
                out.push('\n');
            }
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("kalos-input-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn text_is_cleaned_of_boms_and_cr_line_ends() {
        assert_eq!(clean_text("\u{feff}v 1\nv 2"), "v 1\nv 2");
        assert_eq!(clean_text("a\rb\r\nc\r\rd\r"), "a\nb\nc\n\nd\n");
        assert_eq!(clean_text("a\r\n\r\nb").lines().count(), 3);
        // only a leading BOM is dropped
        assert_eq!(clean_text("a\u{feff}"), "a\u{feff}");
        assert!(matches!(clean_text("plain\n"), Cow::Borrowed(_)));
    }

    #[test]
    fn files_above_the_limit_are_refused_naming_both_sizes() {
        let d = temp("limit");
        let p = d.join("big.obj");
        std::fs::write(&p, vec![b'#'; 2048]).unwrap();
        assert_eq!(read_bytes_limited(&p, 2048).unwrap().len(), 2048);
        let e = read_bytes_limited(&p, 1024).unwrap_err();
        assert!(
            e.contains("big.obj") && e.contains("2 KiB") && e.contains("1 KiB"),
            "{e}"
        );
        assert!(e.contains(MAX_INPUT_ENV), "{e}");
        let e = read_bytes(&d.join("none.obj")).unwrap_err();
        assert!(e.ends_with("none.obj: no such file"), "{e}");
        let e = read_bytes(&d).unwrap_err();
        assert!(e.contains("is a directory"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_named_and_not_read() {
        let e = read_bytes(Path::new("/dev/zero")).unwrap_err();
        assert!(e.starts_with("/dev/zero: is a character device"), "{e}");
        let d = temp("fifo");
        let f = d.join("p.toml");
        assert!(std::process::Command::new("mkfifo")
            .arg(&f)
            .status()
            .unwrap()
            .success());
        let e = read_text(&f).unwrap_err();
        assert!(e.contains("p.toml: is a FIFO"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn sizes_parse_with_suffixes() {
        assert_eq!(parse_size("123").unwrap(), 123);
        assert_eq!(parse_size("2K").unwrap(), 2048);
        assert_eq!(parse_size("1.5g").unwrap(), 3 << 29);
        assert_eq!(parse_size(" 4 M ").unwrap(), 4 << 20);
        for bad in ["", "x", "0", "-1", "1T", "nan", "K"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert_eq!(human_size(17), "17 bytes");
        assert_eq!(human_size(3 << 30), "3 GiB");
        assert_eq!(human_size(1536), "1.5 KiB");
    }
}
