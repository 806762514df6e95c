use super::*;
use clap::ValueEnum;

/// Each mode has one name in scene files (serde), on the command line
/// (clap) and in reports and messages (`as_str`, `Display`); `ALL` lists
/// every variant in order; a misspelt name is refused listing the others.
fn names_agree<T>(all: &[T], name: fn(T) -> &'static str, bad: &[&str])
where
    T: Copy + PartialEq + std::fmt::Debug + std::fmt::Display + ValueEnum,
    T: serde::Serialize + serde::de::DeserializeOwned,
{
    for &m in all {
        let quoted = format!("\"{}\"", name(m));
        assert_eq!(serde_json::from_str::<T>(&quoted).unwrap(), m);
        assert_eq!(serde_json::to_string(&m).unwrap(), quoted);
        assert_eq!(m.to_possible_value().unwrap().get_name(), name(m));
        assert_eq!(m.to_string(), name(m));
    }
    assert_eq!(T::value_variants(), all);
    for b in bad {
        let e = serde_json::from_str::<T>(&format!("{b:?}"))
            .unwrap_err()
            .to_string();
        for &m in all {
            assert!(e.contains(name(m)), "{b:?}: {e}");
        }
    }
}

#[test]
fn boundary_mode_names_agree() {
    names_agree(
        &BoundaryMode::ALL,
        BoundaryMode::as_str,
        &["sphere", "", "None"],
    );
}

#[test]
fn spectral_mode_names_agree() {
    names_agree(
        &SpectralMode::ALL,
        SpectralMode::as_str,
        &["compensate", "", "naive ", "Naive"],
    );
}

#[test]
fn integrator_mode_names_agree() {
    names_agree(
        &IntegratorMode::ALL,
        IntegratorMode::as_str,
        &["photonmap", "", "Path", "path-tracer"],
    );
}
