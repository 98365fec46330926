//! `cargo xtask`: the project's runner (mesh, verify, view, delaunay, regress, bench,
//! paper-table, test).

use clap::{Parser, Subcommand};

/// `println!` that ignores a closed stdout (e.g. `| head`) instead of panicking.
macro_rules! outln {
    () => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout());
    }};
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// `print!` that ignores a closed stdout.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($t)*);
    }};
}

mod cli;
mod suites;

use cli::{delaunay, mesh, verify, view};
use suites::{bench, paper_table, regress, scans, test_all};

#[derive(Parser)]
#[command(
    name = "cargo xtask",
    about = "rdt-mesher runner: mesh surfaces, verify meshes, run suites"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
    /// Worker threads (default: RAYON_NUM_THREADS, else one per core). The results do not
    /// depend on it; 1 runs everything on one core.
    #[arg(long, global = true)]
    threads: Option<usize>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Mesh a surface (default: the catalog torus) and write the mesh and a report.
    Mesh(mesh::MeshArgs),
    /// Verify a triangle mesh (topology, self-intersections, quality; against a surface:
    /// Hausdorff, normals, loose-epsilon certificate).
    Verify(verify::VerifyArgs),
    /// Write one self-contained HTML viewer of a mesh (rotate, zoom, colour by quality,
    /// the report's failing facets highlighted); opens offline in any browser.
    View(view::ViewArgs),
    /// 3D Delaunay triangulation of a point file or of random points.
    Delaunay(delaunay::DelaunayArgs),
    /// Timing tables (medians, ratios against baselines measured in the same run).
    Bench(bench::BenchArgs),
    /// Regression suite over the catalog: guarantees and golden counts.
    Regress(regress::RegressArgs),
    /// Simulated scans of the fixture models: topology and Hausdorff table (GUIDE).
    Scans(scans::ScansArgs),
    /// The paper's Table 1 on this machine (writes docs/paper-table.{json,md}).
    PaperTable(paper_table::PaperTableArgs),
    /// The whole test suite, what CI runs: Rust tests, quick regression, the Python package's
    /// tests, the readers' mutation smoke pass.
    Test(test_all::TestArgs),
}

/// The flags, or exit: a bad value of a numeric flag is one `error:` line (the parser's
/// when it names the flag, as ours do with a valid example; else clap's first line) and
/// status 2, as are two flags that cannot go together (clap's first line, which names
/// both); other usage errors are clap's.
fn parse() -> Cli {
    match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            use std::error::Error as _;
            if matches!(
                e.kind(),
                ErrorKind::ValueValidation | ErrorKind::ArgumentConflict
            ) {
                match e.source().map(|s| s.to_string()) {
                    Some(src) if src.starts_with("--") => eprintln!("error: {src}"),
                    _ => eprintln!("{}", e.to_string().lines().next().unwrap_or("error")),
                }
                std::process::exit(2);
            }
            e.exit()
        }
    }
}

fn main() {
    let cli = parse();
    if let Some(n) = cli.threads {
        let max = cli::output::MAX_THREADS;
        let built = if n == 0 {
            Err("--threads 0: give at least 1 thread".to_string())
        } else if n > max {
            Err(format!(
                "--threads {n}: at most {max} (the results do not depend on the count)"
            ))
        } else {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build_global()
                .map_err(|e| format!("--threads {n}: {e}"))
        };
        if let Err(msg) = built {
            eprintln!("error: {msg}");
            std::process::exit(2);
        }
    }
    // Ok(true): the command ran and its verdict failed (`mesh`; `--strict` exits with 3).
    let r = match &cli.cmd {
        Cmd::Mesh(a) => mesh::run(a).map(|v| !v.passed()),
        Cmd::Delaunay(a) => delaunay::run(a).map(|()| false),
        Cmd::Verify(a) => verify::run(a).map(|()| false),
        Cmd::View(a) => view::run(a).map(|()| false),
        Cmd::Bench(a) => bench::run(a).map(|()| false),
        Cmd::Regress(a) => regress::run(a).map(|()| false),
        Cmd::Scans(a) => scans::run(a).map(|()| false),
        Cmd::PaperTable(a) => paper_table::run(a).map(|()| false),
        Cmd::Test(a) => test_all::run(a).map(|()| false),
    };
    let verdict_failed = match r {
        Ok(failed) => failed,
        Err(e) => {
            // One readable line, non-zero exit.
            let mut msg = format!("{e}");
            let mut src = e.source();
            while let Some(s) = src {
                let t = s.to_string();
                if !msg.contains(&t) {
                    msg.push_str(": ");
                    msg.push_str(&t);
                }
                src = s.source();
            }
            eprintln!("error: {msg}");
            std::process::exit(1);
        }
    };
    if let Cmd::Mesh(a) = &cli.cmd
        && a.strict
        && verdict_failed
    {
        eprintln!("error: --strict: the verification failed or a criterion is unmet (see above)");
        std::process::exit(3);
    }
}
