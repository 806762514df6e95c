//! The outputs opened by the clients users read them with: Spectral Python
//! for the ENVI cubes and OpenEXR's Python binding for the multi-part EXR
//! (both installed from PyPI by `.ci/run`), against littoral's own reader.

use crate::common::{client, minimal_with, render_job, tempdir};
use littoral::scene::{Overrides, Scene};
use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

/// Five bands over a grey floor 4 m deep, seen by 5 x 3 pixels.
fn scene_text() -> String {
    minimal_with(
        r#"
name = "cl"
spectral = { start_nm = 450.0, end_nm = 650.0, bands = 5 }
sky = { radiance = 0.02 }
domain = { size_m = [20.0, 20.0] }
water = { iop = { a = 0.1, b = 0.3 } }
bottom = { depth_m = 4.0, reflectance = 0.2 }
photons = { count = 50000 }
sensor = { pixels = [5, 3] }
"#,
    )
}

const SCRIPT: &str = r#"
import sys, numpy as np, spectral, OpenEXR
base, nb = sys.argv[1], int(sys.argv[2])
cubes = {}
for name, units in [("", "W m-2 sr-1 nm-1"), (".stderr", "W m-2 sr-1 nm-1"),
                    (".lw", "W m-2 sr-1 nm-1"), (".surface", "W m-2 sr-1 nm-1"), (".rrs", "sr-1")]:
    img = spectral.open_image(base + name + ".hdr")
    assert img.shape == (3, 5, nb), img.shape
    assert img.metadata["data units"] == units, img.metadata["data units"]
    assert len(img.metadata["band names"]) == nb
    assert np.allclose(img.bands.centers, np.linspace(450, 650, nb))
    raw = np.fromfile(base + name + ".bsq", "<f4").reshape(nb, 3, 5).transpose(1, 2, 0)
    a = img.load()
    assert np.array_equal(np.asarray(a), raw), name
    cubes[name] = raw
f = OpenEXR.File(base + ".exr")
parts = {p.name(): p for p in f.parts}
for layer, name in [("radiance", ""), ("stderr", ".stderr"), ("lw", ".lw"),
                    ("surface", ".surface"), ("rrs", ".rrs")]:
    p = parts[layer]
    # R_rs is reflective in the spectral layout (T.), the radiances emissive (S0.).
    prefix = "T." if layer == "rrs" else "S0."
    assert all(c.startswith(prefix) for c in p.channels), (layer, list(p.channels))
    assert ("emissiveUnits" in p.header) == (layer != "rrs"), layer
    chans = sorted(p.channels.keys(), key=lambda c: float(c[len(prefix):-2].replace(",", ".")))
    assert len(chans) == nb, chans
    for b, c in enumerate(chans):
        assert np.array_equal(p.channels[c].pixels, cubes[name][:, :, b]), (layer, c)
assert parts["radiance"].header["spectralLayoutVersion"] == "1.0"
assert parts["rrs"].header["units"] == "sr-1", parts["rrs"].header
print("ok")
"#;

/// Spectral Python reads every cube (shape, wavelengths, units as a
/// string, band names) with the same values as the data file, and the
/// OpenEXR binding reads the EXR's five parts with the same values.
#[test]
fn spectral_python_and_openexr_read_the_outputs() {
    if !client(
        "Spectral Python, OpenEXR and numpy (PyPI)",
        &["python3", "-c", "import spectral, OpenEXR, numpy"],
    ) {
        return;
    }
    let dir = tempdir();
    let s = Scene::parse(&scene_text(), Path::new("cl.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("out"), 0);
    let base = r.outputs.hdr.trim_end_matches(".hdr").to_string();
    let mut child = Command::new("python3")
        .args(["-", &base, "5"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(SCRIPT.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "ok",
        "clients failed (spectral and OpenEXR come from PyPI, installed by .ci/run):\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The HTML report opens in headless Chromium (Debian's `chromium`,
/// installed by `.ci/run`) with no console message at all (the page has no
/// scripts, so any message is an error: a failed load, a parse error), and
/// its screenshot is not blank. The page asks for nothing over the network:
/// no scripts, no links, every image inline.
#[test]
fn html_report_opens_in_headless_chromium() {
    if !client("Chromium (Debian's chromium)", &["chromium", "--version"]) {
        return;
    }
    let dir = tempdir();
    let text = format!(
        "{}\n[tally]\ndepths_m = [0.5, 1.5, 3.0]\n\
         [[radiometer]]\ndepth_m = 1.0\nview = \"nadir\"\nposition_m = [10.0, 10.0]\n",
        scene_text()
    );
    let s = Scene::parse(&text, Path::new("cl.toml"), &Overrides::default()).unwrap();
    let r = render_job(&s, &dir.path().join("out"), 0);
    let html = std::fs::read_to_string(&r.outputs.html).unwrap();
    assert!(r.outputs.html.ends_with("cl.html"), "{}", r.outputs.html);
    // Quicklook, R_rs, radiometers, four profiles, K_d, energy budget.
    assert_eq!(html.matches("<svg").count(), 8, "plots in the page");
    assert!(html.contains("src=\"data:image/png;base64,"));
    for remote in [
        "<script",
        "<link",
        "src=\"http",
        "href=\"http",
        "url(",
        "@import",
    ] {
        assert!(
            !html.contains(remote),
            "the page must be self-contained: {remote}"
        );
    }
    for section in [
        "R_rs at five pixels",
        "1 m, looking nadir",
        "K_d",
        "Energy budget",
        "cache hits",
        "estimate.k",
    ] {
        assert!(html.contains(section), "{section} missing from the page");
    }

    let shot = dir.path().join("shot.png");
    let url = format!(
        "file://{}",
        std::fs::canonicalize(&r.outputs.html).unwrap().display()
    );
    let out = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1200,2400",
        ])
        .arg(format!(
            "--user-data-dir={}",
            dir.path().join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(&url)
        .output()
        .expect("chromium (Debian's package) is installed by .ci/run");
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "chromium failed:\n{log}");
    let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
    assert!(console.is_empty(), "console messages: {console:#?}");

    // The screenshot: mostly white page, but plots, text and the quicklook
    // must colour a real share of it, in many colours.
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let pixels = &buf[..info.buffer_size()];
    let mut coloured = 0usize;
    let mut distinct = std::collections::HashSet::new();
    for px in pixels.chunks_exact(channels) {
        if px[..3].iter().any(|&c| c < 235) {
            coloured += 1;
        }
        distinct.insert([px[0] >> 3, px[1] >> 3, px[2] >> 3]);
    }
    let n = pixels.len() / channels;
    assert_eq!(n, 1200 * 2400, "screenshot size");
    assert!(
        coloured * 50 > n,
        "only {coloured} of {n} pixels are not white"
    );
    assert!(distinct.len() > 50, "only {} colours", distinct.len());
}
