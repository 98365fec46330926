//! What `cargo xtask mesh` writes in its JSON report and how it summarizes the genus of many
//! components on one line (ours; shared by the CLI and the Python bindings, so both write the
//! same report). Lists of objects longer than [`LIST_LIMIT`] are cut to their first entries,
//! with the count beside them (`NAME_total`).

use super::{Budgets, Forecast, Input, Outcome, Request};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

/// Per-component (and other per-item) lists of the report keep this many entries.
pub const LIST_LIMIT: usize = 20;

/// `[1]` for one component; `[0 x 448, 1 x 2]` for many, by genus (`?`: not a closed
/// manifold, listed last).
pub fn genus_summary(genera: &[Option<i64>]) -> String {
    if genera.len() == 1 {
        return format!("[{}]", genera[0].map_or("?".into(), |g| g.to_string()));
    }
    let mut by: BTreeMap<Option<i64>, usize> = BTreeMap::new();
    for g in genera {
        *by.entry(*g).or_default() += 1;
    }
    let mut parts: Vec<String> = by
        .iter()
        .filter_map(|(g, n)| g.map(|g| format!("{g} x {n}")))
        .collect();
    if let Some(n) = by.get(&None) {
        parts.push(format!("? x {n}"));
    }
    format!("[{}]", parts.join(", "))
}

/// Cut every array of objects longer than `limit` inside `v` to its first `limit` entries and
/// add `KEY_total` beside it (arrays of numbers, such as histograms, are kept whole, and so
/// is every `checks` array: the certificate's checks are never cut; with 22 checks since
/// 2026-12-07 a limit of 20 dropped `scan-genus` and the last check from image reports).
pub fn bound_lists(v: &mut Value, limit: usize) {
    match v {
        Value::Object(map) => {
            let mut totals = Vec::new();
            for (k, item) in map.iter_mut() {
                if let Value::Array(a) = item
                    && k != "checks"
                    && a.len() > limit
                    && a.iter().any(Value::is_object)
                {
                    totals.push((format!("{k}_total"), a.len()));
                    a.truncate(limit);
                }
                bound_lists(item, limit);
            }
            for (k, n) in totals {
                map.entry(k).or_insert(json!(n));
            }
        }
        Value::Array(a) => a.iter_mut().for_each(|x| bound_lists(x, limit)),
        _ => {}
    }
}

/// The bounding box of the output, `{min, max}`, or null for an empty mesh.
fn bounding_box(out: &Outcome) -> Value {
    let v = &out.mesh.vertices;
    if v.is_empty() {
        return Value::Null;
    }
    let (lo, hi) = v
        .iter()
        .fold((v[0], v[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    json!({ "min": lo.to_array(), "max": hi.to_array() })
}

/// The fields every report carries: the input's figures, the forecast and the budgets.
pub fn common(
    spec: &str,
    out_path: &Path,
    opened: &Input<'_>,
    forecast: Option<&Forecast>,
    budgets: &Budgets,
    out: &Outcome,
) -> serde_json::Map<String, Value> {
    let bs = opened.surface().bounding_sphere();
    let genera = out
        .report
        .as_ref()
        .and_then(|r| r.topology.as_ref())
        .map(|t| t.genera());
    let mut m = serde_json::Map::new();
    m.insert("input".into(), json!(spec));
    m.insert("output".into(), json!(out_path));
    m.insert("input_kind".into(), json!(opened.stats.kind));
    m.insert(
        "iso".into(),
        json!(opened.stats.image.as_ref().map(|i| i.iso)),
    );
    m.insert("input_stats".into(), json!(opened.stats));
    m.insert(
        "bounding_sphere".into(),
        json!({ "center": bs.center.to_array(), "radius": bs.radius }),
    );
    m.insert("bounding_box".into(), bounding_box(out));
    m.insert("forecast".into(), json!(forecast));
    m.insert("budgets".into(), json!(budgets));
    m.insert(
        "genus_summary".into(),
        json!(genera.as_ref().map(|g| genus_summary(g))),
    );
    m.insert("genus".into(), json!(genera));
    m
}

/// The whole report of one run of `request` on `input` (spec `spec`) whose mesh is written to
/// `out_path`: what `cargo xtask mesh --report` writes, for a constant-size or a two-pass run.
///
/// ```
/// use rdt_mesher::pipeline::{plan, report, Input, Request, SizeRequest};
/// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
/// let req = Request { size: SizeRequest::Size(0.3), ..Default::default() };
/// let p = plan(&input, &req).unwrap();
/// let (forecast, budgets) = (p.forecast().copied(), *p.budgets());
/// let out = p.execute(&mut |_| {}).unwrap();
/// let path = std::path::Path::new("sphere.ply");
/// let r = report::mesh_report("implicit:sphere", path, &input, forecast.as_ref(), &budgets,
///                             &req, &out);
/// assert_eq!((r["sigma"].as_f64(), r["oracle"].as_str()), (Some(0.3), Some("bipolar")));
/// ```
pub fn mesh_report(
    spec: &str,
    out_path: &Path,
    input: &Input<'_>,
    forecast: Option<&Forecast>,
    budgets: &Budgets,
    request: &Request,
    out: &Outcome,
) -> Value {
    let base = common(spec, out_path, input, forecast, budgets, out);
    match &out.two_pass {
        None => finish(
            base,
            json!({
                "sigma": out.sigma,
                "angle": request.min_angle_deg,
                "distance": request.max_distance,
                "oracle": request.oracle.name(),
                "manifold": request.manifold,
                "scaffold": request.scaffold,
                "initialization": request.initialization.name(),
                "seed": request.seed,
                "notes": out.notes,
                "stats": out.stats,
                "verify": out.report,
                // The adaptive rounds of an --epsilon without d_M^inf (null otherwise).
                "adaptive": out.adaptive,
            }),
        ),
        Some(tp) => finish(
            base,
            json!({
                "epsilon": tp.epsilon, "dm_inf": tp.dm_inf,
                "initialization": request.initialization.name(),
                "sigma0": tp.sigma0, "eps_prime": tp.eps_prime, "notes": out.notes,
                "first": tp.first.stats, "second": out.stats, "verify": out.report,
                "second_skipped": tp.second_skipped,
            }),
        ),
    }
}

/// Add `fields` to `base`, bound its lists, and return the report.
pub fn finish(mut base: serde_json::Map<String, Value>, fields: Value) -> Value {
    if let Value::Object(f) = fields {
        base.extend(f);
    }
    let mut v = Value::Object(base);
    if let Some(verify) = v.get_mut("verify") {
        bound_lists(verify, LIST_LIMIT);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn genus_is_summarized_by_value() {
        assert_eq!(genus_summary(&[Some(1)]), "[1]");
        assert_eq!(genus_summary(&[None]), "[?]");
        let many: Vec<Option<i64>> = std::iter::repeat_n(Some(0), 448)
            .chain([Some(1), None, Some(1)])
            .collect();
        assert_eq!(genus_summary(&many), "[0 x 448, 1 x 2, ? x 1]");
    }

    #[test]
    fn long_lists_of_objects_are_cut_with_their_total() {
        let comps: Vec<Value> = (0..50).map(|i| json!({ "genus": i })).collect();
        let hist: Vec<Value> = (0..50).map(|i| json!(i)).collect();
        let checks: Vec<Value> = (0..30).map(|i| json!({ "name": i })).collect();
        let mut v = json!({ "topology": { "components": comps }, "histogram": hist,
                            "verify": { "checks": checks } });
        bound_lists(&mut v, 20);
        assert_eq!(v["topology"]["components"].as_array().unwrap().len(), 20);
        assert_eq!(v["topology"]["components_total"], 50);
        assert_eq!(v["histogram"].as_array().unwrap().len(), 50);
        // The certificate's checks are never cut.
        assert_eq!(v["verify"]["checks"].as_array().unwrap().len(), 30);
        assert!(v["verify"].get("checks_total").is_none());
    }
}
