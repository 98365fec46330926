//! `cargo xtask delaunay`: drive the `delaunay3` crate from outside Rust.
//!
//! - `--input points.xyz --output tets.txt`: input is one `x y z` per line (blank lines and
//!   `#` comments ignored); output is one finite tetrahedron per line as four 0-based input
//!   indices (a duplicated point maps to its first occurrence), positively oriented in
//!   `delaunay3`'s convention (`robust::orient3d > 0`, i.e. the fourth point lies opposite to
//!   the normal `(b - a) x (c - a)`). A JSON summary goes to stdout.
//! - `--random N --seed S --distribution cube|sphere|grid`: prints one JSON object with
//!   `points`, `finite_cells`, `seconds` (insertion time) and `valid` (`is_valid()` result,
//!   run when N <= 200000 or with `--validate`, else `null`).
//! - An input with no tetrahedron (no points, fewer than 4 distinct ones, or all on one line
//!   or plane) is an error naming the reason (exit 1, no output file), not a `"valid": true`
//!   triangulation with 0 cells. The output is written atomically and never over the input.

use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Instant;

use crate::cli::points::parse_xyz;
use anyhow::{Context, Result, bail};
use delaunay3::{DVec3, Triangulation};
use geom::SplitMix64;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Distribution {
    /// Uniform in the unit cube.
    Cube,
    /// Uniform on the unit sphere (rounded to f64: not exactly cospherical).
    Sphere,
    /// N distinct points of the smallest integer grid k^3 >= N, chosen by the seed.
    Grid,
}

/// Build a 3D Delaunay triangulation of a point file or of random points.
#[derive(clap::Args, Debug, Clone)]
pub struct DelaunayArgs {
    /// Input points, one `x y z` per line (`#` comments and blank lines ignored).
    #[arg(long, conflicts_with = "random", requires = "output")]
    pub input: Option<PathBuf>,
    /// Output tetrahedra, one per line as four 0-based input indices.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Number of random points to triangulate (1 to 50,000,000: about 14 GB at 280 bytes
    /// a point).
    #[arg(long, value_parser = parse_point_count)]
    pub random: Option<usize>,
    /// Seed of the random points.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Distribution of the random points.
    #[arg(long, value_enum, default_value_t = Distribution::Cube)]
    pub distribution: Distribution,
    /// Run `is_valid()` even for more than 200000 points.
    #[arg(long)]
    pub validate: bool,
}

/// Random points of the given distribution (deterministic in `seed`).
pub fn random_points(n: usize, seed: u64, dist: Distribution) -> Vec<DVec3> {
    let mut r = SplitMix64(seed);
    match dist {
        Distribution::Cube => (0..n)
            .map(|_| DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()))
            .collect(),
        Distribution::Sphere => (0..n)
            .map(|_| {
                loop {
                    let p = DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()) * 2.0 - DVec3::ONE;
                    let l = p.length_squared();
                    if l > 0.0 && l <= 1.0 {
                        break p / l.sqrt();
                    }
                }
            })
            .collect(),
        Distribution::Grid => {
            let mut k = (n as f64).cbrt().round() as usize;
            while k * k * k < n {
                k += 1;
            }
            let mut all: Vec<DVec3> = (0..k * k * k)
                .map(|i| DVec3::new((i % k) as f64, (i / k % k) as f64, (i / (k * k)) as f64))
                .collect();
            for i in (1..all.len()).rev() {
                let j = (r.next_u64() % (i as u64 + 1)) as usize;
                all.swap(i, j);
            }
            all.truncate(n);
            all
        }
    }
}

pub fn run(args: &DelaunayArgs) -> Result<()> {
    if let Some(input) = &args.input {
        let output = args.output.as_ref().context("--input requires --output")?;
        let name = input.display().to_string();
        let text = std::fs::read_to_string(input)
            .with_context(|| format!("cannot read {name} (a UTF-8 text file of `x y z` lines)"))?;
        let pts = parse_xyz(&text, &name)?;
        crate::cli::output::check_outputs(Some(input), &[("--output", output)])?;
        let t0 = Instant::now();
        let mut t = Triangulation::new();
        let ids = t
            .insert_bulk(&pts)
            .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let seconds = t0.elapsed().as_secs_f64();
        if let Some(why) = degenerate(&t, pts.len()) {
            bail!(
                "{name}: {why}; no tetrahedra, {} not written",
                output.display()
            );
        }
        let mut first = vec![u32::MAX; t.num_vertices()];
        for (i, &v) in ids.iter().enumerate() {
            let f = &mut first[v.index()];
            if *f == u32::MAX {
                *f = i as u32;
            }
        }
        crate::cli::output::write_atomically(output, |tmp| {
            let out = std::fs::File::create(tmp)
                .with_context(|| format!("cannot create {}", tmp.display()))?;
            let mut w = BufWriter::new(out);
            for c in t.finite_cells() {
                let [a, b, c, d] = t.cell_vertices(c).map(|v| first[v.index()]);
                writeln!(w, "{a} {b} {c} {d}")?;
            }
            w.flush()
                .with_context(|| format!("cannot write {}", tmp.display()))
        })?;
        let valid = if pts.len() <= 200_000 || args.validate {
            Some(t.is_valid().is_ok())
        } else {
            None
        };
        outln!(
            "{}",
            serde_json::json!({
                "points": pts.len(),
                "vertices": t.num_vertices(),
                "finite_cells": t.num_finite_cells(),
                "seconds": seconds,
                "valid": valid,
            })
        );
        return Ok(());
    }
    let Some(n) = args.random else {
        bail!("give either --input FILE --output FILE or --random N");
    };
    let pts = random_points(n, args.seed, args.distribution);
    let t0 = Instant::now();
    let mut t = Triangulation::new();
    t.insert_bulk(&pts)
        .map_err(|e| anyhow::anyhow!("random points: {e}"))?;
    let seconds = t0.elapsed().as_secs_f64();
    if let Some(why) = degenerate(&t, n) {
        bail!("--random {n}: {why}; give --random 4 or more");
    }
    let valid = if n <= 200_000 || args.validate {
        Some(match t.is_valid() {
            Ok(()) => true,
            Err(e) => {
                eprintln!("invalid triangulation: {e}");
                false
            }
        })
    } else {
        None
    };
    outln!(
        "{}",
        serde_json::json!({
            "points": n,
            "vertices": t.num_vertices(),
            "finite_cells": t.num_finite_cells(),
            "seconds": seconds,
            "points_per_second": n as f64 / seconds.max(1e-12),
            "bytes_per_point": t.memory_bytes() as f64 / n.max(1) as f64,
            "distribution": format!("{:?}", args.distribution).to_lowercase(),
            "seed": args.seed,
            "valid": valid,
        })
    );
    Ok(())
}

/// Why `t` (built from `n` input points) has no tetrahedron, or `None` if it has some: fewer
/// than 4 distinct points, or all of them on one line or one plane. Such an input is an
/// error, not a `"valid": true` triangulation with 0 cells.
pub fn degenerate(t: &Triangulation, n: usize) -> Option<String> {
    let distinct = t.num_vertices();
    let what = match t.dimension() {
        3 => return None,
        _ if n == 0 => "there are no points".to_string(),
        0 if n == 1 => "there is only 1 point".to_string(),
        0 => format!("all {n} points are the same point"),
        1 if distinct == 2 => format!("the {n} points have only 2 distinct positions"),
        1 => format!("the {n} points ({distinct} distinct) all lie on one line"),
        _ if distinct == 3 => format!("the {n} points have only 3 distinct positions"),
        _ => format!("the {n} points ({distinct} distinct) all lie on one plane"),
    };
    Some(format!(
        "{what}: a 3D Delaunay triangulation needs at least 4 points not on one plane"
    ))
}

/// The most random points `--random` accepts (the triangulation takes about 280 bytes a
/// point, so this is about 14 GB).
pub const MAX_RANDOM_POINTS: usize = 50_000_000;

/// `--random N`: a whole number of points, 1 to [`MAX_RANDOM_POINTS`], checked before any
/// allocation.
fn parse_point_count(s: &str) -> Result<usize, String> {
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a whole number of points"))?;
    if n == 0 || n > MAX_RANDOM_POINTS {
        return Err(format!(
            "{n} points: give 1 to {MAX_RANDOM_POINTS} (about 280 bytes a point)"
        ));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_distributions() {
        for d in [Distribution::Cube, Distribution::Sphere, Distribution::Grid] {
            let p = random_points(100, 3, d);
            assert_eq!(p.len(), 100);
            assert_eq!(p, random_points(100, 3, d));
        }
        let g = random_points(27, 1, Distribution::Grid);
        let mut t = Triangulation::new();
        t.insert_bulk(&g).unwrap();
        assert_eq!(t.num_vertices(), 27);
    }
}
