//! Boxes and ellipses in pixel coordinates.
//!
//! Coordinates are continuous: pixel `(i, j)` covers `[i, i+1) × [j, j+1)`, so
//! a box at `x = 10` of width 20 spans pixels 10..=29, as in the OTB format.

use crate::error::RegionError;
use crate::scalar::Real;

/// An axis-aligned box: top-left corner, width and height, in pixels.
///
/// ```
/// use pftrack::BoundingBox;
/// let a = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
/// let b = BoundingBox::new(5.0, 0.0, 10.0, 10.0);
/// // 50 px overlap out of 150 px union.
/// assert!((a.iou(&b) - 1.0 / 3.0).abs() < 1e-6);
/// ```
#[derive(Copy, Clone, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BoundingBox {
    /// Left edge.
    pub x: Real,
    /// Top edge.
    pub y: Real,
    /// Width.
    pub width: Real,
    /// Height.
    pub height: Real,
}

impl BoundingBox {
    /// A box from its top-left corner and size.
    pub const fn new(x: Real, y: Real, width: Real, height: Real) -> Self {
        BoundingBox { x, y, width, height }
    }

    /// The centre point.
    pub fn centre(&self) -> (Real, Real) {
        (self.x + 0.5 * self.width, self.y + 0.5 * self.height)
    }

    /// Area, or 0 for an empty box.
    pub fn area(&self) -> Real {
        if self.width > 0.0 && self.height > 0.0 { self.width * self.height } else { 0.0 }
    }

    /// Intersection over union, in `[0, 1]` (0 when either box is empty).
    pub fn iou(&self, other: &BoundingBox) -> Real {
        let ix = (self.x + self.width).min(other.x + other.width) - self.x.max(other.x);
        let iy = (self.y + self.height).min(other.y + other.height) - self.y.max(other.y);
        if !(ix > 0.0 && iy > 0.0) {
            return 0.0;
        }
        let inter = ix * iy;
        let union = self.area() + other.area() - inter;
        if union > 0.0 { crate::scalar::clamp(inter / union, 0.0, 1.0) } else { 0.0 }
    }

    /// The share of this box's area that `other` covers, in `[0, 1]` (0 for
    /// an empty box).
    pub fn covered_by(&self, other: &BoundingBox) -> Real {
        let ix = (self.x + self.width).min(other.x + other.width) - self.x.max(other.x);
        let iy = (self.y + self.height).min(other.y + other.height) - self.y.max(other.y);
        let area = self.area();
        if !(ix > 0.0 && iy > 0.0 && area > 0.0) {
            return 0.0;
        }
        crate::scalar::clamp(ix * iy / area, 0.0, 1.0)
    }

    /// Checks that the box is usable as a target in a `width × height` frame:
    /// finite, non-empty, no larger than the frame, and overlapping it.
    /// A box that only partly overlaps the frame is accepted as it is (its
    /// histogram uses the pixels inside); nothing is clamped.
    pub fn validate(&self, frame_width: usize, frame_height: usize) -> Result<(), RegionError> {
        let v = [self.x, self.y, self.width, self.height];
        if v.iter().any(|c| !c.is_finite()) {
            return Err(RegionError::NonFinite);
        }
        if !(self.width > 0.0 && self.height > 0.0) {
            return Err(RegionError::EmptyBox);
        }
        if self.width > frame_width as Real || self.height > frame_height as Real {
            return Err(RegionError::LargerThanFrame);
        }
        if self.x >= frame_width as Real
            || self.y >= frame_height as Real
            || self.x + self.width <= 0.0
            || self.y + self.height <= 0.0
        {
            return Err(RegionError::OutsideFrame);
        }
        Ok(())
    }
}

/// An upright ellipse: centre and half axes, in pixels.
#[derive(Copy, Clone, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ellipse {
    /// Centre, x.
    pub cx: Real,
    /// Centre, y.
    pub cy: Real,
    /// Half axis along x.
    pub hx: Real,
    /// Half axis along y.
    pub hy: Real,
}

impl Ellipse {
    /// The ellipse inscribed in a box.
    pub fn from_box(b: &BoundingBox) -> Self {
        let (cx, cy) = b.centre();
        Ellipse { cx, cy, hx: 0.5 * b.width, hy: 0.5 * b.height }
    }

    /// The box the ellipse is inscribed in.
    pub fn to_box(&self) -> BoundingBox {
        BoundingBox::new(self.cx - self.hx, self.cy - self.hy, 2.0 * self.hx, 2.0 * self.hy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_validation_matrix() {
        let ok = BoundingBox::new(10.0, 10.0, 20.0, 20.0);
        assert_eq!(ok.validate(100, 100), Ok(()));
        // Partly outside on the left: accepted, 5 px of it are inside.
        assert_eq!(BoundingBox::new(-15.0, 10.0, 20.0, 20.0).validate(100, 100), Ok(()));
        assert_eq!(BoundingBox::new(0.0, 0.0, 0.0, 5.0).validate(100, 100), Err(RegionError::EmptyBox));
        assert_eq!(BoundingBox::new(0.0, 0.0, -3.0, 5.0).validate(100, 100), Err(RegionError::EmptyBox));
        assert_eq!(BoundingBox::new(Real::NAN, 0.0, 3.0, 5.0).validate(100, 100), Err(RegionError::NonFinite));
        assert_eq!(BoundingBox::new(0.0, 0.0, Real::INFINITY, 5.0).validate(100, 100), Err(RegionError::NonFinite));
        assert_eq!(BoundingBox::new(0.0, 0.0, 101.0, 5.0).validate(100, 100), Err(RegionError::LargerThanFrame));
        assert_eq!(BoundingBox::new(100.0, 0.0, 5.0, 5.0).validate(100, 100), Err(RegionError::OutsideFrame));
        assert_eq!(BoundingBox::new(-5.0, 0.0, 5.0, 5.0).validate(100, 100), Err(RegionError::OutsideFrame));
    }

    #[test]
    fn iou_hand_cases() {
        let a = BoundingBox::new(0.0, 0.0, 10.0, 10.0);
        assert_eq!(a.iou(&a), 1.0);
        assert_eq!(a.iou(&BoundingBox::new(10.0, 0.0, 10.0, 10.0)), 0.0, "touching edges");
        // Quarter overlap: 25 / (100 + 100 - 25).
        let q = a.iou(&BoundingBox::new(5.0, 5.0, 10.0, 10.0));
        assert!((q - 25.0 / 175.0).abs() < 1e-6);
        assert_eq!(a.iou(&BoundingBox::default()), 0.0);
    }

    #[test]
    fn ellipse_box_round_trip() {
        let b = BoundingBox::new(3.0, 4.0, 10.0, 6.0);
        assert_eq!(Ellipse::from_box(&b).to_box(), b);
    }
}
