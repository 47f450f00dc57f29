//! Colour maps for continuous layers.

use super::canvas::Rgb;

/// A colour map from [0, 1] to RGB.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Colormap {
    /// Perceptually uniform dark blue to yellow (matplotlib's default): elevation.
    Viridis,
    /// Black to yellow through red: variance and error magnitude.
    Inferno,
    /// White (free, 0) to black (occupied, 1), as occupancy grids are drawn.
    GreysReversed,
    /// Blue (negative) through white to red (positive): signed error.
    Diverging,
}

const VIRIDIS: [Rgb; 9] = [
    [68, 1, 84],
    [71, 44, 122],
    [59, 81, 139],
    [44, 113, 142],
    [33, 144, 141],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

const INFERNO: [Rgb; 9] = [
    [0, 0, 4],
    [31, 12, 72],
    [85, 15, 109],
    [136, 34, 106],
    [186, 54, 85],
    [227, 89, 51],
    [249, 140, 10],
    [249, 201, 50],
    [252, 255, 164],
];

const DIVERGING: [Rgb; 5] = [
    [33, 102, 172],
    [146, 197, 222],
    [247, 247, 247],
    [244, 165, 130],
    [178, 24, 43],
];

fn interpolate(stops: &[Rgb], t: f32) -> Rgb {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (stops.len() - 1) as f32;
    let k = (x.floor() as usize).min(stops.len() - 2);
    let f = x - k as f32;
    let (a, b) = (stops[k], stops[k + 1]);
    [0, 1, 2].map(|c| (f32::from(a[c]) + (f32::from(b[c]) - f32::from(a[c])) * f).round() as u8)
}

impl Colormap {
    /// The colour of `t` in [0, 1] (clamped; NaN maps to 0).
    pub fn color(self, t: f32) -> Rgb {
        match self {
            Self::Viridis => interpolate(&VIRIDIS, t),
            Self::Inferno => interpolate(&INFERNO, t),
            Self::GreysReversed => interpolate(&[[255, 255, 255], [0, 0, 0]], t),
            Self::Diverging => interpolate(&DIVERGING, t),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_and_clamping() {
        assert_eq!(Colormap::Viridis.color(0.0), VIRIDIS[0]);
        assert_eq!(Colormap::Viridis.color(1.0), VIRIDIS[8]);
        assert_eq!(Colormap::Viridis.color(7.0), VIRIDIS[8]);
        assert_eq!(Colormap::GreysReversed.color(0.0), [255, 255, 255]);
        assert_eq!(Colormap::GreysReversed.color(0.5), [128, 128, 128]);
        assert_eq!(Colormap::Diverging.color(0.5), [247, 247, 247]);
        assert_eq!(Colormap::Inferno.color(f32::NAN), INFERNO[0]);
    }
}
