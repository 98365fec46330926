//! `cargo xtask mesh --epsilon` without d_M^inf (or with `--adaptive`): the lines of the
//! adaptive mode (`rdt_mesher::adaptive`, after the paper's section 6.5): one per round, and
//! a summary with the certificate's achieved epsilon.

use rdt_mesher::adaptive::{EarlyStop, Round};
use rdt_mesher::pipeline::Outcome;

/// The line of one round, printed before it runs.
pub fn round_line(r: &Round) -> String {
    format!(
        "round {} (from round {}'s {} vertices): d_M^inf estimate {:.4}, sigma = max({:.5}, \
         eps' d_M){}, {} medial points, {:.2} s",
        r.round,
        r.round.saturating_sub(1),
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
    } else if let Some(stop) = a.early_stop {
        let (next, last) = (a.rounds.len(), a.rounds.len().saturating_sub(1));
        match stop {
            EarlyStop::OverBudget { vertices } => format!(
                "stopped before round {next}: it should need about {vertices} vertices, over \
                 the vertex budget (--max-vertices); the output is round {last}'s, complete"
            ),
            EarlyStop::BelowPrecision {
                dm_inf,
                at,
                tolerance,
            } => format!(
                "stopped before round {next}: the d_M estimate falls to {dm_inf:.3e} at \
                 ({:.4}, {:.4}, {:.4}), within 100 times the oracle's precision {tolerance:.1e} \
                 (a singular point of S: no eps-sample is in reach; --size gives a uniform \
                 mesh); the output is round {last}'s, complete",
                at[0], at[1], at[2]
            ),
        }
    } else if let Some(s) = &out.stats.stopped_by {
        format!("stopped by {s}")
    } else {
        "round limit".to_string()
    };
    format!(
        "{spec}: adaptive eps = {} ({} rounds, {how}): sigma = max({:.5}, {:.4} d_M), d_M^inf \
         estimate {:.4}; {achieved} (d_M by Voronoi poles of the final sample)",
        a.epsilon,
        // (Round 0 and the rounds estimated, but for one not started.)
        a.rounds.len() + usize::from(!a.last_estimate_only),
        a.floor,
        a.eps_prime,
        a.dm_inf_estimate
    )
}
