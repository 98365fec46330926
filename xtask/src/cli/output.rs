//! (ours) Writing what a command produces without losing anything: outputs are written to a
//! temporary file in the destination folder and renamed over the final path, so a run killed
//! while writing leaves either the previous file or the new one, never a truncated one; and
//! no output may be the input or another output of the same run.
//!
//! Also the value parsers of the numeric flags (`--time-limit`, `--size`, `--angle`,
//! `--epsilon`, `--max-memory`, ...), so clap reports a bad value as a usage error naming the
//! flag and a valid example.

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// The most worker threads `--threads` accepts (checked in `main`).
pub const MAX_THREADS: usize = 256;

/// The longest `--time-limit` accepted, in seconds (a year).
pub const MAX_SECONDS: f64 = 365.0 * 24.0 * 3600.0;

/// `--time-limit S`: a finite number of seconds in (0, a year].
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| {
        format!("--time-limit {s}: not a number of seconds (e.g. --time-limit 60 or 2.5)")
    })?;
    if !(v.is_finite() && v > 0.0 && v <= MAX_SECONDS) {
        return Err(format!(
            "--time-limit {s}: give a positive, finite number of seconds, at most {MAX_SECONDS} (a year), e.g. --time-limit 60"
        ));
    }
    Ok(v)
}

/// A parser of a positive, finite number for `flag` (`example`: a valid value).
pub fn positive(
    flag: &'static str,
    what: &'static str,
    example: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: f64 = s.trim().parse().map_err(|_| {
            format!(
                "{flag} {s}: not a number; {what} must be a positive number, e.g. {flag} {example}"
            )
        })?;
        if !(v.is_finite() && v > 0.0) {
            return Err(format!(
                "{flag} {s}: {what} must be a positive number, e.g. {flag} {example}"
            ));
        }
        Ok(v)
    }
}

/// `--angle DEG`: in [0, 35) (30 has a termination proof; 0 disables the criterion).
pub fn parse_angle(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().unwrap_or(f64::NAN);
    if !(0.0..35.0).contains(&v) {
        return Err(format!(
            "--angle {s}: the facet angle bound must be in [0, 35) degrees (30, the default, \
             has a termination proof; 0 turns it off), e.g. --angle 30"
        ));
    }
    Ok(v)
}

/// `--epsilon E` and `--certify-epsilon E`: in (0, 1).
pub fn epsilon(
    flag: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: f64 = s.trim().parse().unwrap_or(f64::NAN);
        if !(v > 0.0 && v < 1.0) {
            return Err(format!(
                "{flag} {s}: epsilon must be in (0, 1), e.g. {flag} 0.09"
            ));
        }
        Ok(v)
    }
}

/// `--max-memory SIZE`: `2G`, `500M`, ... (binary units), see `rdt_mesher::pipeline::parse_bytes`.
pub fn parse_memory(s: &str) -> Result<u64, String> {
    rdt_mesher::pipeline::parse_bytes(s).map_err(|e| format!("--max-memory {s}: {e}"))
}

/// `--max-vertices N`: at least 1.
pub fn parse_max_vertices(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!(
            "--max-vertices {s}: give a positive whole number of vertices, e.g. --max-vertices 200000"
        )),
    }
}

/// The absolute, normalized form of a path that may not exist yet (its folder may not
/// either): the longest existing ancestor is canonicalized, the rest appended.
fn normalized(p: &Path) -> PathBuf {
    let joined = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    // `.` and `..` resolved lexically first (a folder named in the path may not exist).
    let mut abs = PathBuf::new();
    for c in joined.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                abs.pop();
            }
            other => abs.push(other),
        }
    }
    let mut tail = Vec::new();
    let mut head = abs.as_path();
    loop {
        if let Ok(c) = head.canonicalize() {
            return tail.iter().rev().fold(c, |acc: PathBuf, t| acc.join(t));
        }
        match (head.parent(), head.file_name()) {
            (Some(parent), Some(name)) => {
                tail.push(name.to_os_string());
                head = parent;
            }
            _ => return abs,
        }
    }
}

/// Refuse a run whose outputs would overwrite its input or each other, or whose mesh
/// output (flag `-o`, as `mesh` passes it) has no mesh extension: checked before any work,
/// not after meshing.
/// `outputs` are (flag, path) pairs, e.g. `("-o", mesh)`, `("--report", report)`.
pub fn check_outputs(input: Option<&Path>, outputs: &[(&str, &Path)]) -> Result<()> {
    for &(flag, p) in outputs {
        if flag == "-o" && meshio::Format::from_path(p).is_err() {
            let ext = p.extension().map(|e| e.to_string_lossy().into_owned());
            bail!(
                "{flag} {}: {}; the mesh formats are .ply, .off, .obj, .stl, .glb, .vtk, \
                 .vtp and .gii (e.g. {flag} {}.ply)",
                p.display(),
                ext.map_or("no file extension".to_string(), |e| format!(
                    "unknown mesh file extension \"{e}\""
                )),
                p.with_extension("").display()
            );
        }
    }
    let norm: Vec<(&str, &Path, PathBuf)> = outputs
        .iter()
        .map(|&(f, p)| (f, p, normalized(p)))
        .collect();
    if let Some(inp) = input.filter(|p| p.exists()) {
        let i = normalized(inp);
        for (flag, p, n) in &norm {
            if *n == i {
                bail!(
                    "{flag} {}: that is the input file; write the output elsewhere (e.g. {flag} out/{})",
                    p.display(),
                    p.file_name()
                        .map_or("mesh.ply".into(), |f| f.to_string_lossy())
                );
            }
        }
    }
    for (k, (f1, p1, n1)) in norm.iter().enumerate() {
        for (f2, _, n2) in &norm[k + 1..] {
            if n1 == n2 {
                bail!(
                    "{f1} and {f2} both name {}: give each output its own file",
                    p1.display()
                );
            }
        }
    }
    Ok(())
}

/// Write `path` through `write(tmp)`: `tmp` is a new file beside `path` with the same
/// extension (none if `path` has none); it is renamed over `path` once `write` succeeded,
/// and removed if it failed. Errors name `path`, not the temporary.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file name", path.display()))?
        .to_string_lossy()
        .into_owned();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    // `.NAME.PID.tmp.EXT`, or `.NAME-PID-tmp` (no dot after the name) when it has no
    // extension: the temporary has the same extension as `path`, or none.
    let tmp = if ext.is_empty() {
        dir.join(format!(".{name}-{}-tmp", std::process::id()))
    } else {
        dir.join(format!(".{name}.{}.tmp{ext}", std::process::id()))
    };
    let result = write(&tmp)
        .map_err(|e| naming(e, &tmp, path))
        .and_then(|()| {
            std::fs::rename(&tmp, path)
                .with_context(|| format!("cannot move {} to {}", tmp.display(), path.display()))
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `e` as one line (each cause once, as `main` prints it) with `tmp` replaced by `path`.
fn naming(e: anyhow::Error, tmp: &Path, path: &Path) -> anyhow::Error {
    let (t, p) = (tmp.display().to_string(), path.display().to_string());
    let mut msg = String::new();
    for cause in e.chain() {
        let c = cause.to_string().replace(&t, &p);
        if !msg.contains(&c) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(&c);
        }
    }
    anyhow::anyhow!(msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numeric_flags_are_checked() {
        for bad in ["-1", "0", "nan", "inf", "1e300", "x", ""] {
            assert!(parse_seconds(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_seconds("2.5"), Ok(2.5));
        let size = positive("--size", "the size bound", "0.05");
        for bad in ["-inf", "nan", "0", "-1", "x"] {
            let e = size(bad).unwrap_err();
            assert!(
                e.starts_with(&format!("--size {bad}:")) && e.contains("--size 0.05"),
                "{e}"
            );
        }
        assert_eq!(size("0.2"), Ok(0.2));
        for bad in ["100", "35", "-1", "nan"] {
            assert!(
                parse_angle(bad).unwrap_err().contains("e.g. --angle 30"),
                "{bad}"
            );
        }
        assert_eq!(parse_angle("0"), Ok(0.0));
        assert!(epsilon("--epsilon")("1.5").is_err() && epsilon("--epsilon")("0.2").is_ok());
        assert_eq!(parse_memory("2G"), Ok(2 << 30));
        assert!(
            parse_memory("-2G")
                .unwrap_err()
                .starts_with("--max-memory -2G")
        );
        assert!(parse_max_vertices("0").is_err() && parse_max_vertices("10") == Ok(10));
    }

    #[test]
    fn outputs_may_not_overwrite_the_input_or_each_other() {
        let d = std::env::temp_dir().join(format!("xtask-out-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let input = d.join("in.ply");
        std::fs::write(&input, "x").unwrap();
        let same = d.join("sub/../in.ply");
        let e = check_outputs(Some(&input), &[("-o", &same)]).unwrap_err();
        assert!(e.to_string().contains("that is the input file"), "{e}");
        let m = d.join("new/m.ply");
        let e = check_outputs(None, &[("-o", &m), ("--report", &m)]).unwrap_err();
        assert!(e.to_string().contains("-o and --report both name"), "{e}");
        check_outputs(Some(&input), &[("-o", &m), ("--report", &d.join("r.json"))]).unwrap();
        // A failed write leaves the old file and no temporary behind.
        let out = d.join("keep.ply");
        std::fs::write(&out, "old").unwrap();
        let r = write_atomically(&out, |tmp| {
            std::fs::write(tmp, "partial")?;
            bail!("interrupted")
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            2,
            "no temporary left"
        );
        write_atomically(&out, |tmp| Ok(std::fs::write(tmp, "new")?)).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
        // The temporary keeps the extension (or the lack of one); errors name the final path.
        for (name, ext) in [("m.ply", Some("ply")), ("noext", None)] {
            let p = d.join(name);
            let e = write_atomically(&p, |tmp| {
                assert_eq!(
                    tmp.extension().and_then(|e| e.to_str()),
                    ext,
                    "{}",
                    tmp.display()
                );
                meshio::read(tmp)?; // no such file: an error naming `tmp`
                Ok(())
            })
            .unwrap_err()
            .to_string();
            assert!(
                e.contains(&p.display().to_string()) && !e.contains("-tmp"),
                "{e}"
            );
        }
        // A mesh output without a mesh extension is refused before any work.
        for bad in ["out/m.abc", "out/m"] {
            let e = check_outputs(None, &[("-o", Path::new(bad))]).unwrap_err();
            let e = e.to_string();
            assert!(
                e.starts_with(&format!("-o {bad}: ")) && e.contains(".stl"),
                "{e}"
            );
        }
        check_outputs(None, &[("--report", Path::new("r.json"))]).unwrap();
        std::fs::remove_dir_all(&d).unwrap();
    }
}
