use super::*;

#[test]
fn even_grid_spans_the_range() {
    let g = BandGrid::even(400.0, 700.0, 16).unwrap();
    assert_eq!(g.len(), 16);
    assert_eq!(g.centers_nm()[0], 400.0);
    assert!((g.centers_nm()[15] - 700.0).abs() < 1e-3);
    assert!((g.fwhm_nm()[3] - 20.0).abs() < 1e-4);
}

#[test]
fn bad_grids_are_rejected_with_the_field() {
    assert!(BandGrid::even(400.0, 700.0, 0).is_err());
    let e = BandGrid::explicit(vec![500.0, 490.0], vec![10.0, 10.0]).unwrap_err();
    assert!(e.to_string().contains("centers_nm[1]"), "{e}");
    let e = BandGrid::explicit(vec![500.0], vec![0.0]).unwrap_err();
    assert!(e.to_string().contains("fwhm_nm[0]"), "{e}");
}
