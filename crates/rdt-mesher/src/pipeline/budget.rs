//! The budgets of a run and the default size (ours; section 6.5's sigma = 0.09 d_M^inf where
//! it is affordable): a requested size whose [`Forecast`] exceeds a budget is refused before
//! refining, with the size that fits; without a size, the theorems' default is kept when its
//! forecast is at most [`AUTO_MAX_VERTICES`], else a size forecasting
//! [`AUTO_TARGET_VERTICES`] is chosen (images: at least half the voxel spacing).
//!
//! Invariant: a planned run's mesher stops at [`Budgets::mesher_cap`] vertices, so a forecast
//! that was too low still ends with a valid mesh and the criteria it left unmet.

use super::error::PipelineError;
use super::forecast::{AreaEstimate, Forecast, count, round_up_3, sig, vertices_for_memory};
use super::input::Input;
use super::request::Request;
use std::fmt;

/// The vertex budget when [`Request::max_vertices`] is not given: a requested size
/// forecasting more is refused (about 3 GiB).
pub const DEFAULT_MAX_VERTICES: usize = 2_000_000;

/// The memory budget when [`Request::max_memory`] is not given, in bytes (4 GiB).
pub const DEFAULT_MAX_MEMORY: u64 = 4 << 30;

/// No size requested: the theorems' default is kept up to this forecast.
pub const AUTO_MAX_VERTICES: u64 = 100_000;

/// No size requested and the theorems' default forecasts too many vertices: the size chosen
/// forecasts this many (images: unless half the voxel spacing is coarser).
pub const AUTO_TARGET_VERTICES: u64 = 30_000;

/// The budgets of a request, defaults applied.
///
/// ```
/// use rdt_mesher::pipeline::{Budgets, Request, DEFAULT_MAX_VERTICES};
/// let b = Budgets::of(&Request::default());
/// assert_eq!((b.max_vertices, b.vertices_given), (DEFAULT_MAX_VERTICES, false));
/// assert_eq!(b.mesher_cap(), DEFAULT_MAX_VERTICES);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Budgets {
    /// The vertex budget.
    pub max_vertices: usize,
    /// It was requested ([`Request::max_vertices`]): the run stops there, and a forecast above
    /// it is not refused.
    pub vertices_given: bool,
    /// The memory budget, in bytes.
    pub max_memory: u64,
    /// It was requested ([`Request::max_memory`]).
    pub memory_given: bool,
}

/// The budget a forecast exceeds.
///
/// ```
/// use rdt_mesher::pipeline::Budget;
/// assert_eq!(Budget::Memory(2 << 30).to_string(), "the memory budget of 2.0 GiB");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Budget {
    /// The default vertex budget ([`DEFAULT_MAX_VERTICES`] unless requested).
    Vertices(usize),
    /// The memory budget, in bytes.
    Memory(u64),
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Budget::Vertices(n) => write!(f, "the vertex budget of {}", count(*n as u64)),
            Budget::Memory(b) => write!(f, "the memory budget of {}", super::forecast::bytes(*b)),
        }
    }
}

impl Budgets {
    /// The budgets of `request` ([`DEFAULT_MAX_VERTICES`], [`DEFAULT_MAX_MEMORY`] when not
    /// given).
    pub fn of(request: &Request) -> Budgets {
        Budgets {
            max_vertices: request.max_vertices.unwrap_or(DEFAULT_MAX_VERTICES),
            vertices_given: request.max_vertices.is_some(),
            max_memory: request.max_memory.unwrap_or(DEFAULT_MAX_MEMORY),
            memory_given: request.max_memory.is_some(),
        }
    }

    /// Where the mesher stops: the vertex budget, or fewer if the memory budget affords fewer.
    pub fn mesher_cap(&self) -> usize {
        let mem = vertices_for_memory(self.max_memory).min(usize::MAX as u64) as usize;
        self.max_vertices.min(mem.max(1))
    }

    /// The budget `f` exceeds, if any: the vertex budget when it was not requested (a
    /// requested one stops the run instead: see [`Request::max_vertices`]), else the memory
    /// budget.
    ///
    /// ```
    /// use rdt_mesher::pipeline::{AreaEstimate, AreaSource, Budget, Budgets, Forecast, Request};
    /// let sphere = AreaEstimate { area: 4.0 * std::f64::consts::PI, source: AreaSource::InputTriangles };
    /// let b = Budgets::of(&Request::default());
    /// assert_eq!(b.exceeded_by(&Forecast::at(sphere, 0.05)), None);
    /// // A thousandth of the radius forecasts about 8 million vertices: over the default budget.
    /// assert_eq!(
    ///     b.exceeded_by(&Forecast::at(sphere, 0.001)),
    ///     Some(Budget::Vertices(rdt_mesher::pipeline::DEFAULT_MAX_VERTICES))
    /// );
    /// // A requested vertex budget stops the run instead; memory still refuses.
    /// let given = Budgets::of(&Request { max_vertices: Some(100), ..Request::default() });
    /// assert!(matches!(given.exceeded_by(&Forecast::at(sphere, 0.001)), Some(Budget::Memory(_))));
    /// ```
    pub fn exceeded_by(&self, f: &Forecast) -> Option<Budget> {
        if !self.vertices_given && f.vertices > self.max_vertices as u64 {
            Some(Budget::Vertices(self.max_vertices))
        } else if f.memory_bytes > self.max_memory {
            Some(Budget::Memory(self.max_memory))
        } else {
            None
        }
    }

    /// The most vertices a forecast may have and not be refused.
    fn affordable(&self) -> u64 {
        let mem = vertices_for_memory(self.max_memory);
        if self.vertices_given {
            mem
        } else {
            mem.min(self.max_vertices as u64)
        }
    }
}

/// Refuse `sigma` (requested, or the first pass's sigma_0 with `dm_inf` in two-pass mode)
/// when its forecast exceeds a budget; otherwise return the forecast and the notes to add.
pub(crate) fn check(
    input: &Input<'_>,
    area: Option<AreaEstimate>,
    sigma: f64,
    budgets: &Budgets,
    dm_inf: Option<f64>,
) -> Result<(Option<Forecast>, Vec<String>), PipelineError> {
    let Some(area) = area else {
        return Ok((None, vec![no_forecast()]));
    };
    let f = Forecast::at(area, sigma);
    if let Some(budget) = budgets.exceeded_by(&f) {
        let fits = round_up_3(Forecast::size_for(area.area, budgets.affordable()));
        return Err(PipelineError::OverBudget {
            input: input.name.clone(),
            forecast: f,
            budget,
            fits,
            dm_inf,
        });
    }
    Ok((Some(f), stop_note(&f, budgets).into_iter().collect()))
}

fn no_forecast() -> String {
    "forecast: not available (the coarse mesh that estimates the area failed); the budgets \
     are checked while meshing"
        .into()
}

/// A note when the run will reach the mesher's cap before its criteria hold.
fn stop_note(f: &Forecast, budgets: &Budgets) -> Option<String> {
    let cap = budgets.mesher_cap();
    (f.vertices > cap as u64).then(|| {
        format!(
            "the forecast ({} vertices) is above the vertex budget ({cap}{}): the run will \
             stop there with criteria unmet",
            count(f.vertices),
            if cap < budgets.max_vertices {
                ", what the memory budget affords"
            } else {
                ""
            }
        )
    })
}

/// The size of [`SizeRequest::Auto`](super::SizeRequest::Auto), its forecast and the notes
/// saying which rule chose it and why.
pub(crate) fn auto_size(
    input: &Input<'_>,
    area: Option<AreaEstimate>,
    budgets: &Budgets,
) -> (f64, Option<Forecast>, Vec<String>) {
    let (sigma, rule, kept, theorem) = theorem_default(input);
    let Some(area) = area else {
        return (sigma, None, vec![kept, no_forecast()]);
    };
    let f = Forecast::at(area, sigma);
    let affordable = budgets.affordable();
    if f.vertices <= AUTO_MAX_VERTICES.min(affordable) {
        return (sigma, Some(f), vec![kept]);
    }
    let target = AUTO_TARGET_VERTICES.min(affordable);
    let by_count = round_up_3(Forecast::size_for(area.area, target));
    let floor = input.voxel_spacing.map(|h| round_up_3(0.5 * h));
    let chosen = floor.map_or(by_count, |h| by_count.max(h));
    let why = match floor {
        Some(h) if h >= by_count => format!(
            "half the voxel spacing: finer sizes add little of the image, but a handle of S \
             thinner than that needs one (verify's scan-genus counts them); {} vertices would \
             take sigma = {}",
            count(target),
            sig(by_count)
        ),
        _ => format!("the size forecasting {} vertices", count(target)),
    };
    let cf = Forecast::at(area, chosen);
    let mut note = format!(
        "no --size: {rule} = {} forecasts {} vertices, over the default's limit of {}: using \
         sigma = {} instead ({why}), forecast {} vertices",
        sig(sigma),
        count(f.vertices),
        count(AUTO_MAX_VERTICES.min(affordable)),
        sig(chosen),
        count(cf.vertices)
    );
    // Said when it matters: 20% above (not a slightly anisotropic voxel's geometric mean).
    if let Some(fine) = input.voxel_spacing_min.map(|h| round_up_3(0.5 * h))
        && chosen > 1.2 * fine
    {
        note.push_str(&format!(
            "; sigma is above half the smallest voxel spacing ({}): parts of S thinner than \
             that can be split, missed or lose handles (--size {} forecasts {} vertices)",
            sig(fine),
            sig(fine),
            count(Forecast::at(area, fine).vertices)
        ));
    }
    if theorem {
        note.push_str(
            "; the theorems' sampling condition (sigma <= 0.09 d_M^inf) is not claimed at this \
             size: request the size to get it",
        );
    }
    (chosen, Some(cf), vec![note])
}

/// The size the paper's rules give without a request, the rule's name, the note saying it
/// was used, and whether it is the theorems' sigma = 0.09 d_M^inf.
fn theorem_default(input: &Input<'_>) -> (f64, &'static str, String, bool) {
    match (input.default_size, input.dm_inf()) {
        (Some(d), _) => (
            d,
            "the input's suggested size",
            format!("no --size: using the input's suggested size {d:.5}"),
            false,
        ),
        (None, Some(dm)) => (
            0.09 * dm,
            "sigma = 0.09 * d_M^inf",
            format!("no --size: using sigma = 0.09 * d_M^inf = {:.5}", 0.09 * dm),
            true,
        ),
        (None, None) => {
            let r = input.surface().bounding_sphere().radius / 20.0;
            (
                r,
                "sigma = bounding radius / 20",
                format!("no --size: using sigma = bounding radius / 20 = {r:.5}"),
                false,
            )
        }
    }
}
