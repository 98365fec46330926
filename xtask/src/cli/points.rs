//! Point files given on the command line (ours): `mesh --initial-points` and `delaunay
//! --input` read `x y z` lines. (One place for both readers, until one `.xyz` reader serves
//! the whole workspace.)

use anyhow::{Context, Result, bail};
use glam::DVec3;
use std::path::PathBuf;

/// `--initial-points`: one `x y z` per line (blank lines and `#` lines skipped; extra columns
/// ignored); errors name the file and the line.
pub fn read_xyz(path: &PathBuf) -> Result<Vec<DVec3>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut pts = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .take(3)
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                anyhow::anyhow!(
                    "{}:{}: expected `x y z`, found '{l}'",
                    path.display(),
                    i + 1
                )
            })?;
        if v.len() < 3 || v.iter().any(|x| !x.is_finite()) {
            bail!(
                "{}:{}: expected three finite numbers `x y z`, found '{l}'",
                path.display(),
                i + 1
            );
        }
        pts.push(DVec3::new(v[0], v[1], v[2]));
    }
    Ok(pts)
}

/// Parses an `.xyz` text: one `x y z` per line; errors name the file and line.
pub fn parse_xyz(text: &str, name: &str) -> Result<Vec<DVec3>> {
    let mut pts = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.len() != 3 {
            bail!(
                "{name}:{}: expected 3 numbers `x y z`, found {} fields in {line:?}",
                i + 1,
                fields.len()
            );
        }
        let mut c = [0.0; 3];
        for (k, f) in fields.iter().enumerate() {
            c[k] = f.parse::<f64>().map_err(|e| {
                anyhow::anyhow!(
                    "{name}:{}: field {} {f:?} is not a number: {e}",
                    i + 1,
                    k + 1
                )
            })?;
        }
        let p = DVec3::from_array(c);
        delaunay3::validate_point(p).map_err(|e| anyhow::anyhow!("{name}:{}: {e}", i + 1))?;
        pts.push(p);
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_errors_name_the_line() {
        let e = parse_xyz("0 0 0\n# c\n\n1 2\n", "f.xyz").unwrap_err();
        assert!(e.to_string().contains("f.xyz:4"), "{e}");
        let e = parse_xyz("0 0 0\n1 x 2\n", "f.xyz").unwrap_err();
        assert!(e.to_string().contains("f.xyz:2: field 2"), "{e}");
        let e = parse_xyz("0 0 0\n1 inf 2\n", "f.xyz").unwrap_err();
        assert!(e.to_string().contains("f.xyz:2: point"), "{e}");
        let p = parse_xyz("1 2 3 # a point\n\n4 5 6\n", "f").unwrap();
        assert_eq!(
            p,
            vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)]
        );
    }
}
