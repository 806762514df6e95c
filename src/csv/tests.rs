use super::*;

fn p(text: &str) -> Result<CsvTable> {
    parse(text, Path::new("t.csv"), "sun.spectrum")
}

/// Parse and read every field as a number.
fn all(text: &str) -> Result<Vec<Vec<f64>>> {
    let t = p(text)?;
    t.rows.iter().map(|r| t.numbers(r)).collect()
}

#[test]
fn header_comments_blank_lines_and_separators() {
    let t = p("# source: test\n\nnm, value\n400,0.5 # first\n500 0.25\n\n600,\t1e-3\n").unwrap();
    assert_eq!(t.header, Some((3, vec!["nm".into(), "value".into()])));
    assert_eq!(t.width(), 2);
    let rows: Vec<(usize, Vec<f64>)> = t
        .rows
        .iter()
        .map(|r| (r.line, t.numbers(r).unwrap()))
        .collect();
    assert_eq!(
        rows,
        vec![
            (4, vec![400.0, 0.5]),
            (5, vec![500.0, 0.25]),
            (7, vec![600.0, 1e-3])
        ]
    );
    assert_eq!(t.column("value").unwrap(), 1);
    t.expect_header(&["nm", "value"]).unwrap();
    t.expect_width(2, "2 fields").unwrap();
}

#[test]
fn every_error_names_file_line_and_field() {
    for (text, line, what) in [
        ("400,0.1\n4OO,0.2\n", 2, "'4OO' is not a finite number"),
        (
            "nm,v\n400,0.1\n500\n",
            3,
            "1 fields, but line 2 has 2 fields",
        ),
        ("400,nan\n", 1, "'nan' is not a finite number"),
        ("400,,1\n", 1, "empty field"),
    ] {
        let e = all(text).unwrap_err().to_string();
        assert!(
            e.contains("t.csv")
                && e.contains(&format!("line {line}:"))
                && e.contains("sun.spectrum")
                && e.contains(what),
            "{text:?}: {e}"
        );
    }
    // A first row with one number is data, not a header.
    assert!(all("4OO,0.1\n").unwrap_err().to_string().contains("'4OO'"));
    // Columns a reader does not use may hold text.
    let t = p("nm,a,source\n400,0.1,PopeFry1997\n").unwrap();
    assert_eq!(t.number(&t.rows[0], 1).unwrap(), 0.1);
    let t = p("a,b\n1,2\n").unwrap();
    assert!(t
        .column("c")
        .unwrap_err()
        .to_string()
        .contains("line 1: sun.spectrum: header has no column 'c'"));
    assert!(t
        .expect_header(&["x", "y"])
        .unwrap_err()
        .to_string()
        .contains("header must be x,y"));
    assert!(t
        .expect_width(3, "3 fields")
        .unwrap_err()
        .to_string()
        .contains("expected 3 fields, found 2"));
    let e = read(Path::new("/nonexistent/t.csv"), "f")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/t.csv"), "{e}");
}
