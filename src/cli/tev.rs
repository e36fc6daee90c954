//! `kalos render --tev [HOST:PORT]`: the image streamed to a running tev viewer
//! (github.com/Tom94/tev) as passes finish, over tev's TCP protocol: every packet is its
//! length (u32, little-endian, these 4 bytes included), its type (u8) and its payload;
//! strings end with a zero byte, integers and floats are little-endian.
//!
//! - CreateImage (4): grab focus (u8), name, width, height, channel count (i32), the
//!   channel names;
//! - UpdateImage (3): grab focus (u8), name, channel name, x, y, width, height (i32),
//!   width * height f32 values of that channel, row-major.
//!
//! A tev that does not answer costs one warning line; the render goes on without it.

use crate::progress::Progress;
use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Where tev listens unless told otherwise.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:14158";

/// At most this often an image is sent during a render (the last one always).
const MIN_INTERVAL: Duration = Duration::from_millis(250);

/// Values per UpdateImage packet at most: a large image goes in strips of rows.
const MAX_VALUES: usize = 1 << 20;

const CHANNELS: [&str; 3] = ["R", "G", "B"];

fn put_str(b: &mut Vec<u8>, s: &str) {
    b.extend_from_slice(s.as_bytes());
    b.push(0);
}

fn put_i32(b: &mut Vec<u8>, v: i32) {
    b.extend_from_slice(&v.to_le_bytes());
}

fn packet(kind: u8, payload: Vec<u8>) -> Vec<u8> {
    let mut p = Vec::with_capacity(payload.len() + 5);
    p.extend_from_slice(&((payload.len() + 5) as u32).to_le_bytes());
    p.push(kind);
    p.extend(payload);
    p
}

/// The CreateImage packet of an RGB image.
pub fn create_image(name: &str, width: u32, height: u32) -> Vec<u8> {
    let mut b = vec![0u8]; // do not grab the focus
    put_str(&mut b, name);
    put_i32(&mut b, width as i32);
    put_i32(&mut b, height as i32);
    put_i32(&mut b, CHANNELS.len() as i32);
    for c in CHANNELS {
        put_str(&mut b, c);
    }
    packet(4, b)
}

/// The UpdateImage packets of an RGB image: per strip of rows, one per channel.
pub fn update_image(name: &str, width: u32, height: u32, rgb: &[[f32; 3]]) -> Vec<Vec<u8>> {
    let rows_per = (MAX_VALUES / width.max(1) as usize).max(1);
    let mut out = Vec::new();
    let mut y0 = 0usize;
    while y0 < height as usize {
        let rows = rows_per.min(height as usize - y0);
        for (k, c) in CHANNELS.iter().enumerate() {
            let mut b = vec![0u8];
            put_str(&mut b, name);
            put_str(&mut b, c);
            put_i32(&mut b, 0);
            put_i32(&mut b, y0 as i32);
            put_i32(&mut b, width as i32);
            put_i32(&mut b, rows as i32);
            let px = &rgb[y0 * width as usize..(y0 + rows) * width as usize];
            for p in px {
                b.extend_from_slice(&p[k].to_le_bytes());
            }
            out.push(packet(3, b));
        }
        y0 += rows;
    }
    out
}

/// A connection to tev, if one could be made.
struct Link {
    stream: TcpStream,
    /// The image's size once created in tev.
    created: Option<(u32, u32)>,
    last: Option<Instant>,
}

/// A [`Progress`] that also streams each pass's image to tev, and forwards everything
/// else to the progress it wraps.
pub struct TevProgress<'a> {
    inner: &'a dyn Progress,
    name: String,
    link: Mutex<Option<Link>>,
}

/// Check `HOST:PORT` of `--tev` (one line naming the option when it is not one).
pub fn parse_address(s: &str) -> Result<String, String> {
    match s.rsplit_once(':') {
        Some((host, port)) if !host.is_empty() && port.parse::<u16>().is_ok() => Ok(s.into()),
        _ => Err(format!(
            "--tev {s}: expected HOST:PORT (tev listens on {DEFAULT_ADDRESS} unless started with --hostname)"
        )),
    }
}

impl<'a> TevProgress<'a> {
    /// Connect to tev at `address` (1 s at most); when it does not answer, say so on one
    /// line and render without it. `name` is the image's name in tev.
    pub fn connect(inner: &'a dyn Progress, address: &str, name: &str) -> TevProgress<'a> {
        let stream = address
            .to_socket_addrs()
            .map_err(|e| e.to_string())
            .and_then(|mut a| a.next().ok_or_else(|| "no address".to_string()))
            .and_then(|a| {
                TcpStream::connect_timeout(&a, Duration::from_secs(1)).map_err(|e| e.to_string())
            });
        let link = match stream {
            Ok(stream) => {
                let _ = stream.set_nodelay(true);
                let _ = stream.set_write_timeout(Some(Duration::from_secs(5)));
                Some(Link {
                    stream,
                    created: None,
                    last: None,
                })
            }
            Err(e) => {
                eprintln!(
                    "kalos: warning: --tev {address}: no tev viewer answers ({e}); rendering without the live preview"
                );
                None
            }
        };
        TevProgress {
            inner,
            name: name.to_string(),
            link: Mutex::new(link),
        }
    }

    /// Send an image now (the final one: always, however soon after the last).
    pub fn send(&self, width: u32, height: u32, rgb: &[[f32; 3]]) {
        self.send_if(width, height, &|| rgb.to_vec(), true)
    }

    fn send_if(&self, width: u32, height: u32, image: &dyn Fn() -> Vec<[f32; 3]>, force: bool) {
        let mut guard = match self.link.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        let Some(link) = guard.as_mut() else { return };
        if !force && link.last.is_some_and(|t| t.elapsed() < MIN_INTERVAL) {
            return;
        }
        let rgb = image();
        if rgb.len() != width as usize * height as usize {
            return;
        }
        let mut packets = Vec::new();
        if link.created != Some((width, height)) {
            packets.push(create_image(&self.name, width, height));
        }
        packets.extend(update_image(&self.name, width, height, &rgb));
        let sent = packets.iter().try_for_each(|p| link.stream.write_all(p));
        match sent {
            Ok(()) => {
                link.created = Some((width, height));
                link.last = Some(Instant::now());
            }
            Err(e) => {
                eprintln!("kalos: warning: --tev: the viewer stopped answering ({e}); rendering on without it");
                *guard = None;
            }
        }
    }
}

impl Progress for TevProgress<'_> {
    fn begin(&self, unit: &str, total: u64) {
        self.inner.begin(unit, total)
    }
    fn set_total(&self, samples: u64) {
        self.inner.set_total(samples)
    }
    fn advance(&self, samples: u64) {
        self.inner.advance(samples)
    }
    fn message(&self, text: &str) {
        self.inner.message(text)
    }
    fn finish(&self) {
        self.inner.finish()
    }
    fn cancelled(&self) -> bool {
        self.inner.cancelled()
    }
    fn pass_image(&self, width: u32, height: u32, image: &dyn Fn() -> Vec<[f32; 3]>) {
        self.send_if(width, height, image, false)
    }
}
