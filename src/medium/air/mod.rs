//! Real air (`docs/air.md`): a temperature field, a pressure, a humidity and
//! a wavelength, turned into δ = n − 1 by a published formula.
//!
//! ```text
//! T(h, x, z) = base + lapse·h                      (or "standard": the US 1976 layers)
//!            + exponential.delta · e^(−h/exponential.scale_height)
//!            + inversion.delta · σ((h − inversion.height)/inversion.thickness)
//!            + Σ_j hotspots[j].delta · w_j(x, z) · e^(−h/hotspots[j].scale_height)
//!   (or a measured table of [h, T] rows, a shape-preserving cubic, plus hot spots)
//! P(h)       = pressure · exp(−(gM/R)∫₀^h dh'/T_u)  (hydrostatic, over the uniform part)
//! RH(h)      = humidity (one number) or a measured table of [h, RH] rows (the same cubic)
//! n − 1      = Ciddor 1996 | Edlén (Birch & Downs) | Gladstone–Dale K·(P/101325)/T
//! ```
//!
//! | parameter | unit | meaning (default) |
//! | --- | --- | --- |
//! | `air.temperature.base` | °C | T at h = 0 (15) |
//! | `air.temperature.lapse` | K/m | dT/dh, or `"standard"` (none) |
//! | `air.temperature.exponential.delta`, `.scale_height` | K, m | surface layer |
//! | `air.temperature.inversion.delta`, `.height`, `.thickness` | K, m, m | step aloft |
//! | `air.temperature.table[i][0]`, `[i][1]` | m, °C | a measured profile |
//! | `air.pressure` | Pa | at h = 0 (101325); `hydrostatic` (true) |
//! | `air.humidity` | – | relative, 0…1 (0) |
//! | `air.humidity.table[i][0]`, `[i][1]` | m, – | a measured humidity profile |
//! | `air.wavelength` | nm | vacuum (550) |
//! | `air.co2` | ppm | by mole, Ciddor only (450) |
//! | `air.refractivity.gladstone_dale` | K | with `{"gladstone_dale": K}` |
//! | `hotspots[j].x`, `.z`, `.radius`, `.edge` | m, m, m, 1/m | as in the logistic model |
//! | `hotspots[j].delta`, `.scale_height` | K, m | excess at the ground, its decay |
//!
//! ```json
//! { "air": { "temperature": { "base": 10.033,
//!                             "exponential": { "delta": 3.15, "scale_height": 0.0497512 } },
//!            "pressure": 101325.0, "hydrostatic": false,
//!            "refractivity": { "gladstone_dale": 0.079386 } } }
//! ```
//!
//! Files: `model` (the parameters and their file form), `access` (by path),
//! `checks` (validation), `field` (the compiled δ and ∇δ), `bounds` (the
//! envelope), and the physics each uses: `refractivity` and `humidity` (the
//! formulas), `standard` (US 1976), `pchip` (the table's cubic),
//! `hydrostatic` (the pressure).

mod access;
mod bounds;
mod checks;
mod field;
pub mod humidity;
pub mod hydrostatic;
mod model;
pub mod pchip;
pub mod refractivity;
pub mod standard;

pub use checks::WAVELENGTH_RANGE;
pub use field::{AirField, COLDEST, HOTTEST, KELVIN};
pub(crate) use field::{LaneTerms, UniformTerms};
pub use model::{
    Air, AirHotSpot, AirMedium, DEFAULT_BASE, DEFAULT_CO2, DEFAULT_PRESSURE, DEFAULT_WAVELENGTH,
    Exponential, Humidity, Lapse, Step, Temperature,
};
pub use refractivity::{AirState, Formula};
