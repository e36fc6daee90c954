//! `kalos render --tev`: the packets a fake tev server on 127.0.0.1 records, checked
//! against tev's protocol and against the image the render writes; and a tev that is not
//! running costs one warning line, not the render.

use std::io::Read;
use std::net::TcpListener;
use std::process::Command;

/// One packet: (type, payload).
fn packets(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 5 <= bytes.len() {
        let len = u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap()) as usize;
        assert!(
            len >= 5 && i + len <= bytes.len(),
            "a packet of {len} bytes at {i} overruns the stream"
        );
        out.push((bytes[i + 4], bytes[i + 5..i + len].to_vec()));
        i += len;
    }
    assert_eq!(i, bytes.len(), "trailing bytes after the last packet");
    out
}

struct Reader<'a>(&'a [u8]);
impl Reader<'_> {
    fn u8(&mut self) -> u8 {
        let v = self.0[0];
        self.0 = &self.0[1..];
        v
    }
    fn i32(&mut self) -> i32 {
        let v = i32::from_le_bytes(self.0[..4].try_into().unwrap());
        self.0 = &self.0[4..];
        v
    }
    fn f32(&mut self) -> f32 {
        f32::from_bits(self.i32() as u32)
    }
    fn str(&mut self) -> String {
        let n = self
            .0
            .iter()
            .position(|&b| b == 0)
            .expect("a string without its zero byte");
        let s = String::from_utf8(self.0[..n].to_vec()).unwrap();
        self.0 = &self.0[n + 1..];
        s
    }
}

fn temp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("kalos-tev-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `kalos render cornell --res RES --spp SPP -q --tev 127.0.0.1:PORT -o OUT`.
fn render_to_tev(res: &str, spp: &str, port: u16, out: &std::path::Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args([
            "render", "cornell", "--method", "plain", "--res", res, "--spp", spp, "-q", "--tev",
        ])
        .arg(format!("127.0.0.1:{port}"))
        .arg("-o")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn render_streams_passes_to_tev() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut all = Vec::new();
        s.read_to_end(&mut all).unwrap();
        all
    });
    let dir = temp("stream");
    let out = dir.join("live.exr");
    let st = render_to_tev("24x16", "64", port, &out);
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    assert!(
        st.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let ps = packets(&server.join().unwrap());
    // CreateImage first: no focus grab, the output's name, 24x16, R G B
    let (kind, body) = &ps[0];
    assert_eq!(*kind, 4);
    let mut r = Reader(body);
    assert_eq!(r.u8(), 0);
    assert_eq!(r.str(), "live.exr");
    assert_eq!((r.i32(), r.i32(), r.i32()), (24, 16, 3));
    assert_eq!(
        (r.str(), r.str(), r.str()),
        ("R".into(), "G".into(), "B".into())
    );
    assert!(r.0.is_empty());
    // then UpdateImage packets, one per channel: at least a pass and the final image
    let updates: Vec<_> = ps[1..].iter().collect();
    assert!(
        updates.iter().all(|p| p.0 == 3),
        "only updates after the creation"
    );
    assert!(
        updates.len() >= 6 && updates.len() % 3 == 0,
        "{} updates",
        updates.len()
    );
    let image = kalos::image_io::read_image(&out).unwrap();
    for (k, (_, body)) in updates[updates.len() - 3..].iter().enumerate() {
        let mut r = Reader(body);
        assert_eq!(r.u8(), 0);
        assert_eq!(r.str(), "live.exr");
        assert_eq!(r.str(), ["R", "G", "B"][k]);
        assert_eq!((r.i32(), r.i32(), r.i32(), r.i32()), (0, 0, 24, 16));
        // the last update is the written image, exactly
        for p in &image.data {
            assert_eq!(r.f32(), p[k]);
        }
        assert!(r.0.is_empty());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_tev_that_is_not_running_costs_one_warning() {
    // a port just freed: nothing listens there
    let port = TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let dir = temp("absent");
    let out = dir.join("a.exr");
    let st = render_to_tev("16x16", "2", port, &out);
    assert!(st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("kalos: warning: --tev 127.0.0.1:") && err.contains("without"),
        "{err}"
    );
    assert!(out.exists());
    // and an address that is none is refused on one line
    let st = Command::new(env!("CARGO_BIN_EXE_kalos"))
        .args(["render", "cornell", "--tev", "nowhere", "-o"])
        .arg(dir.join("b.exr"))
        .output()
        .unwrap();
    assert_eq!(st.status.code(), Some(2));
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("--tev nowhere: expected HOST:PORT"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
