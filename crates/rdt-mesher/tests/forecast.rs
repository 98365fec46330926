//! The forecast, the budgets and the default size of `rdt_mesher::pipeline` (issue 15).

use rdt_mesher::StopReason;
use rdt_mesher::pipeline::{
    AUTO_MAX_VERTICES, Budget, DEFAULT_MAX_VERTICES, Forecast, Input, PipelineError, Request,
    SizeRequest, plan, run,
};

fn sized(s: f64) -> Request {
    Request {
        size: SizeRequest::Size(s),
        verify: false,
        ..Default::default()
    }
}

/// The forecast is within 10% of the vertex count on smooth catalog surfaces and a mesh.
#[test]
fn forecast_is_close_to_the_count() {
    let dir = env!("CARGO_MANIFEST_DIR");
    for (spec, size) in [
        ("implicit:sphere".to_string(), 0.05),
        ("implicit:torus".to_string(), 0.02),
        ("implicit:tanglecube".to_string(), 0.08),
        (format!("{dir}/../../fixtures/models/bunny.ply"), 0.003),
    ] {
        let input = Input::open(&spec, &Default::default()).unwrap();
        let req = sized(size);
        let p = plan(&input, &req).unwrap();
        let f = *p.forecast().expect("a forecast");
        let out = p.execute(&mut |_| {}).unwrap();
        let ratio = f.vertices as f64 / out.stats.vertices as f64;
        assert!(
            (0.9..1.1).contains(&ratio),
            "{spec}: {f} vs {}",
            out.stats.vertices
        );
    }
}

/// A size over the default vertex budget is refused before meshing, with a size that fits;
/// that size is accepted.
#[test]
fn over_budget_sizes_are_refused_with_one_that_fits() {
    let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    let e = plan(&input, &sized(0.001)).err().expect("refused");
    let PipelineError::OverBudget {
        forecast,
        budget,
        fits,
        ..
    } = e
    else {
        panic!("{e}")
    };
    assert_eq!(budget, Budget::Vertices(DEFAULT_MAX_VERTICES));
    assert!(forecast.vertices > DEFAULT_MAX_VERTICES as u64);
    let f = Forecast::at(forecast.area, fits);
    assert!(f.vertices <= DEFAULT_MAX_VERTICES as u64, "{f}");
    assert!(plan(&input, &sized(fits)).is_ok());
    // A memory budget refuses too, naming itself.
    let req = Request {
        max_memory: Some(20 << 20),
        ..sized(0.01)
    };
    let e = plan(&input, &req).err().expect("refused");
    assert!(
        matches!(e, PipelineError::OverBudget { budget: Budget::Memory(b), .. } if b == 20 << 20)
    );
    assert!(e.to_string().contains("memory budget of 20 MiB"), "{e}");
}

/// A requested vertex budget is a stop: the run is planned with a note, stops there, and
/// returns a non-empty mesh with its unmet criteria; the default cap is the default budget.
#[test]
fn requested_vertex_budget_stops_the_run() {
    let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    let req = Request {
        max_vertices: Some(2000),
        ..sized(0.01)
    };
    let p = plan(&input, &req).unwrap();
    assert!(
        p.notes().iter().any(|n| n.contains("will stop there")),
        "{:?}",
        p.notes()
    );
    let out = p.execute(&mut |_| {}).unwrap();
    assert_eq!(
        out.stats.stopped_by,
        Some(StopReason::MaxVertices { limit: 2000 })
    );
    assert!(!out.mesh.triangles.is_empty() && !out.stats.unmet.is_empty());
    assert!(!out.verdict.passed());
    let coarse = sized(0.3);
    let p = plan(&input, &coarse).unwrap();
    assert_eq!(p.mesh_options().max_vertices, Some(DEFAULT_MAX_VERTICES));
    let small = Request {
        max_memory: Some(1 << 30),
        ..sized(0.3)
    };
    let cap = plan(&input, &small)
        .unwrap()
        .mesh_options()
        .max_vertices
        .unwrap();
    assert!(cap < DEFAULT_MAX_VERTICES && rdt_mesher::pipeline::memory_for(cap as u64) <= 1 << 30);
}

/// Without a size, the theorems' default is kept where it is affordable (the torus: the
/// same mesh as the size requested), and replaced by an affordable size otherwise (the
/// torus with a tiny memory budget), with a note saying why.
#[test]
fn default_size_is_kept_when_affordable_and_replaced_otherwise() {
    let input = Input::open("implicit:torus", &Default::default()).unwrap();
    let auto = Request {
        verify: false,
        ..Default::default()
    };
    let p = plan(&input, &auto).unwrap();
    assert_eq!(p.sigma(), Some(0.09 * 0.3));
    assert!(p.forecast().unwrap().vertices <= AUTO_MAX_VERTICES);
    let a = run(&input, &auto).unwrap();
    let b = run(&input, &sized(0.09 * 0.3)).unwrap();
    assert_eq!(a.mesh, b.mesh);
    let tight = Request {
        max_memory: Some(20 << 20),
        ..auto
    };
    let p = plan(&input, &tight).unwrap();
    let f = p.forecast().unwrap();
    assert!(
        p.sigma().unwrap() > 0.027 && f.memory_bytes <= 20 << 20,
        "{f}"
    );
    let note = p.notes().last().unwrap();
    assert!(
        note.contains("instead") && note.contains("not claimed"),
        "{note}"
    );
}

/// Two passes: the first pass's size is what the budget checks.
#[test]
fn two_pass_first_pass_is_checked() {
    let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    let req = Request {
        size: SizeRequest::Epsilon {
            epsilon: 0.001,
            dm_inf: None,
        },
        ..Default::default()
    };
    let e = plan(&input, &req).err().expect("refused");
    assert!(
        matches!(e, PipelineError::OverBudget { dm_inf: Some(d), .. } if d == 1.0),
        "{e}"
    );
}

/// An image whose default size is set by the vertex count, above half its smallest voxel
/// spacing, says so and gives the finer size with its forecast: the T1 crop at iso 171.2
/// (1 mm voxels, the size forecasting 30k vertices about 0.9); not the phantom, whose
/// default is half its (6, 6.5, 6) mm voxels already. Half a voxel
/// resolved two FAILs of the default-size sweep (a brain mask's genus, 135 of 168 handles at
/// 1.25 voxel and all at 1); it is said, not imposed (the count grows 1.5-2x there).
#[test]
fn a_default_size_above_half_the_smallest_voxel_says_so() {
    use oracle::image::{ImageOptions, LoadOptions};
    use rdt_mesher::pipeline::InputOptions;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/mni_t1_crop56.nii.gz"
    );
    let opts = InputOptions {
        image: ImageOptions {
            iso: Some(171.2),
            ..Default::default()
        },
        load: LoadOptions::default(),
        ..Default::default()
    };
    let input = Input::open(path, &opts).unwrap();
    let auto = Request {
        verify: false,
        ..Default::default()
    };
    let p = plan(&input, &auto).unwrap();
    let note = p.notes().last().unwrap();
    assert!(p.sigma().unwrap() > 0.6, "{note}");
    assert!(
        note.contains("sigma is above half the smallest voxel spacing (0.500)")
            && note.contains("(--size 0.500 forecasts"),
        "{note}"
    );
    // Where half a voxel is the size chosen, nothing is added.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/phantom_i16_32.nii.gz"
    );
    let opts = InputOptions {
        image: ImageOptions {
            iso: Some(300.0),
            ..Default::default()
        },
        ..Default::default()
    };
    let phantom = Input::open(path, &opts).unwrap();
    let p = plan(&phantom, &auto).unwrap();
    let note = p.notes().last().unwrap();
    assert!(!note.contains("smallest voxel spacing"), "{note}");
}
