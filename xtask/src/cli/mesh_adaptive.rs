//! `cargo xtask mesh --epsilon` without d_M^inf (or with `--adaptive`): the lines of the
//! adaptive mode (`rdt_mesher::adaptive`, after the paper's section 6.5): one per round, and
//! a summary with the certificate's achieved epsilon.

use rdt_mesher::adaptive::Round;
use rdt_mesher::pipeline::Outcome;

/// The line of one round, printed before it runs.
pub fn round_line(r: &Round) -> String {
    format!(
        "round {}: {} vertices, d_M^inf estimate {:.4}, sigma = max({:.5}, eps' d_M){}, \
         {} medial points, {:.2} s",
        r.round,
        r.vertices,
        r.dm_inf_estimate,
        r.floor,
        if r.capped {
            " (floor held at 1/4 of the last)"
        } else {
            ""
        },
        r.medial_points,
        r.seconds
    )
}

/// The summary of an adaptive run (before the single-pass lines).
pub fn summary(spec: &str, out: &Outcome) -> String {
    let a = out.adaptive.as_ref().expect("an adaptive outcome");
    let achieved = out
        .report
        .as_ref()
        .and_then(|r| r.certificate.as_ref())
        .map_or("not verified".to_string(), |c| {
            format!("achieved eps {:.4}", c.eps_achieved)
        });
    let how = if a.converged {
        "stable estimate".to_string()
    } else if let Some(s) = &out.stats.stopped_by {
        format!("stopped by {s}")
    } else {
        "round limit".to_string()
    };
    format!(
        "{spec}: adaptive eps = {} ({} rounds, {how}): sigma = max({:.5}, {:.4} d_M), d_M^inf \
         estimate {:.4}; {achieved} (d_M by Voronoi poles of the final sample)",
        a.epsilon,
        a.rounds.len() + 1,
        a.floor,
        a.eps_prime,
        a.dm_inf_estimate
    )
}
