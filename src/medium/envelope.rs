//! What a consumer that steps through the air needs to know beyond δ and ∇δ:
//! bounds on n and on |∇δ| above the ground, the vertical features of the
//! stratified part, and the patches where δ also varies horizontally. Each kind
//! computes its own [`Envelope`]; the renderer turns it into step sizes, zones
//! and Snell decisions without knowing the kind.

/// Bounds and features of a medium above the ground (y ≥ 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Envelope {
    /// An upper bound of n.
    pub n_max: f64,
    /// A lower bound of n (> 0).
    pub n_min: f64,
    /// An upper bound of |∇δ| (per metre).
    pub gradient_max: f64,
    /// The stratified part's vertical features; empty when it has none.
    pub layers: Vec<VerticalFeature>,
    /// Where δ also depends on (x, z); empty for a stratified medium.
    pub patches: Vec<Patch>,
}

/// A vertical feature of the stratified part of δ: δ changes over `scale`
/// metres around `centre`, and is constant to far below image precision
/// beyond a few tens of `scale` from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VerticalFeature {
    /// Length over which δ changes (metres, > 0).
    pub scale: f64,
    /// Height the change is centred on (metres).
    pub centre: f64,
}

/// A circular patch of ground over which δ depends on (x, z): a logistic hot
/// spot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// Centre x (metres).
    pub x: f64,
    /// Centre z (metres).
    pub z: f64,
    /// Radius (metres).
    pub radius: f64,
    /// Rim sharpness (1/metre): the patch's weight falls from 1 to 0 over a few
    /// 1/edge around the radius.
    pub edge: f64,
    /// Vertical rate (metres): negative for a layer that dies out upward over
    /// |rate|, positive for one that grows upward (it never dies out).
    pub rate: f64,
}
