use super::*;

fn parse(text: &str) -> Result<SpectralResponse> {
    let t = csv::parse(text, Path::new("test.csv"), "sensor")?;
    SpectralResponse::from_table(&t, "test".into())
}

/// 1 nm bands from `from` to `to` nm (centres at the half nanometres).
fn grid(from: u32, to: u32) -> BandGrid {
    let centres: Vec<f32> = (from..to).map(|nm| nm as f32 + 0.5).collect();
    let widths = vec![1.0; centres.len()];
    BandGrid::explicit(centres, widths).unwrap()
}

/// Every shipped sensor parses; Sentinel-2A's visible bands sit at the
/// central wavelengths ESA publishes for them (492.4, 559.8 and 664.6 nm,
/// within 1 nm) and Landsat 8 OLI's at USGS's (482, 561.5 and 654.5 nm).
#[test]
fn shipped_sensors_have_their_published_band_centres() {
    for name in SpectralResponse::names() {
        let s = SpectralResponse::named(name).unwrap();
        assert!(!s.bands.is_empty(), "{name}");
    }
    let s2 = SpectralResponse::named("sentinel2a-msi").unwrap();
    for (band, nm) in [("B2", 492.4), ("B3", 559.8), ("B4", 664.6)] {
        let b = s2.bands.iter().find(|b| b.name == band).unwrap();
        assert!((b.centre_nm - nm).abs() < 1.0, "{band}: {}", b.centre_nm);
    }
    let l8 = SpectralResponse::named("landsat8-oli").unwrap();
    for (band, nm) in [("B2", 482.0), ("B3", 561.5), ("B4", 654.5)] {
        let b = l8.bands.iter().find(|b| b.name == band).unwrap();
        assert!((b.centre_nm - nm).abs() < 1.5, "{band}: {}", b.centre_nm);
    }
    assert_eq!(
        SpectralResponse::named("aviris-ng").unwrap().bands.len(),
        425
    );
    // hGRS's EnMAP (pre-launch, VNIR then SWIR) and PRISMA channels.
    let enmap = SpectralResponse::named("enmap").unwrap();
    assert_eq!(enmap.bands.len(), 242);
    assert!((enmap.bands[0].centre_nm - 423.03).abs() < 0.01);
    let prisma = SpectralResponse::named("prisma").unwrap();
    assert_eq!(prisma.bands.len(), 232);
    assert!((prisma.bands[0].centre_nm - 406.99).abs() < 0.01);
}

/// A triangle from 500 to 510 nm (peak at 505) over 1 nm bands: each
/// band's weight is the triangle's area over it, by hand 0.1, 0.3, 0.5,
/// 0.7, 0.9, 0.9, 0.7, 0.5, 0.3, 0.1 (of 5), so a spectrum equal to the
/// band index reads sum(i w_i) / 5 = 4.5 + 10 (the bands start at 490).
#[test]
fn weights_are_the_response_integrated_over_each_band() {
    let mut text = String::from("wavelength_nm,T\n");
    for nm in 495..=515 {
        let r = (1.0 - (nm as f64 - 505.0).abs() / 5.0).max(0.0);
        text += &format!("{nm},{r}\n");
    }
    let s = parse(&text).unwrap();
    assert!((s.bands[0].centre_nm - 505.0).abs() < 1e-12);
    let w = s.weights(&grid(490, 530));
    assert_eq!(w.len(), 1);
    let hand = [0.1, 0.3, 0.5, 0.7, 0.9, 0.9, 0.7, 0.5, 0.3, 0.1];
    assert_eq!(w[0].weights.len(), 10);
    for ((b, got), want) in w[0].weights.iter().zip(hand) {
        assert!((got - want / 5.0).abs() < 1e-12, "band {b}: {got}");
    }
    let value: f64 = w[0].weights.iter().map(|(b, w)| *b as f64 * w).sum();
    assert!((value - 14.5).abs() < 1e-12, "{value}");
}

/// Weights sum to one, so a flat spectrum resamples to itself; a Gaussian
/// band reads a linear spectrum at its centre (it is symmetric).
#[test]
fn a_flat_spectrum_resamples_to_itself() {
    let s = parse("band,center_nm,fwhm_nm\nb1,450,10\nb2,600.3,7.5\n").unwrap();
    let g = grid(400, 700);
    let w = s.weights(&g);
    assert_eq!(w.len(), 2);
    for bw in &w {
        let sum: f64 = bw.weights.iter().map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-12);
        let linear: f64 = bw
            .weights
            .iter()
            .map(|(b, w)| g.centers_nm()[*b] as f64 * w)
            .sum();
        let centre = s.bands[bw.band].centre_nm;
        assert!((linear - centre).abs() < 1e-3, "{linear} vs {centre}");
    }
}

/// A band whose response reaches past the cube's range is left out.
#[test]
fn bands_outside_the_cube_are_left_out() {
    let s = parse("band,center_nm,fwhm_nm\nin,500,10\nedge,402,10\nout,900,10\n").unwrap();
    let w = s.weights(&grid(400, 800));
    let kept: Vec<&str> = w.iter().map(|b| s.bands[b.band].name.as_str()).collect();
    assert_eq!(kept, ["in"]);
}

/// Unknown and unshipped sensors and malformed tables are errors that say
/// what is wrong.
#[test]
fn bad_sensors_are_named_errors() {
    let e = SpectralResponse::named("pace-oci").unwrap_err().to_string();
    assert!(e.contains("pace-oci") && e.contains("csv:FILE"), "{e}");
    let e = SpectralResponse::named("nosuch").unwrap_err().to_string();
    assert!(
        e.contains("unknown sensor") && e.contains("sentinel2a-msi"),
        "{e}"
    );
    let e = parse("a,b\n1,2\n").unwrap_err().to_string();
    assert!(e.contains("header"), "{e}");
    let e = parse("wavelength_nm,X\n500,0.5\n501,-1\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("negative") && e.contains("line 3"), "{e}");
    let e = parse("wavelength_nm,X\n500,0.5\n502,1\n503,1\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("even steps"), "{e}");
    let e = SpectralResponse::named("csv:/nonexistent/srf.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/srf.csv"), "{e}");
}
