//! Placing text labels next to markers without overlaps: each label tries a list of
//! positions around its marker and takes the first that is inside the area and clear of
//! every marker and every label placed before it.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::PlotError;

/// A rectangle in pixels, `x0 <= x1`, `y0 <= y1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rect {
    pub(crate) x0: i32,
    pub(crate) y0: i32,
    pub(crate) x1: i32,
    pub(crate) y1: i32,
}

impl Rect {
    /// The square of half-side `r` around a point.
    pub(crate) fn around((x, y): (i32, i32), r: i32) -> Self {
        Rect {
            x0: x - r,
            y0: y - r,
            x1: x + r,
            y1: y + r,
        }
    }

    fn overlaps(&self, other: &Rect) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }

    fn inside(&self, bounds: &Rect) -> bool {
        self.x0 >= bounds.x0 && self.x1 <= bounds.x1 && self.y0 >= bounds.y0 && self.y1 <= bounds.y1
    }
}

/// Where a label may go relative to its marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Side {
    Right,
    Left,
    Above,
    Below,
    AboveRight,
    BelowRight,
    AboveLeft,
    BelowLeft,
}

impl Side {
    /// Every side, the most readable first.
    pub(crate) const ALL: [Side; 8] = [
        Side::Right,
        Side::Above,
        Side::Below,
        Side::Left,
        Side::AboveRight,
        Side::BelowRight,
        Side::AboveLeft,
        Side::BelowLeft,
    ];

    /// Text anchor and anchor point for a marker at `(x, y)` with labels `gap` pixels away.
    fn anchor(self, (x, y): (i32, i32), gap: i32) -> (Pos, (i32, i32)) {
        let (h, dx) = match self {
            Side::Right | Side::AboveRight | Side::BelowRight => (HPos::Left, gap),
            Side::Left | Side::AboveLeft | Side::BelowLeft => (HPos::Right, -gap),
            Side::Above | Side::Below => (HPos::Center, 0),
        };
        let (v, dy) = match self {
            Side::Above | Side::AboveRight | Side::AboveLeft => (VPos::Bottom, -gap),
            Side::Below | Side::BelowRight | Side::BelowLeft => (VPos::Top, gap),
            Side::Right | Side::Left => (VPos::Center, 0),
        };
        (Pos::new(h, v), (x + dx, y + dy))
    }
}

/// The box a text of `size` covers when anchored at `point` with `pos`.
fn text_box(pos: Pos, (x, y): (i32, i32), (w, h): (i32, i32)) -> Rect {
    let x0 = match pos.h_pos {
        HPos::Left => x,
        HPos::Center => x - w / 2,
        HPos::Right => x - w,
    };
    let y0 = match pos.v_pos {
        VPos::Top => y,
        VPos::Center => y - h / 2,
        VPos::Bottom => y - h,
    };
    Rect {
        x0,
        y0,
        x1: x0 + w,
        y1: y0 + h,
    }
}

/// Labels placed so far, and the markers they must not cover.
pub(crate) struct LabelPlacer {
    bounds: Rect,
    taken: Vec<Rect>,
}

impl LabelPlacer {
    /// A placer for labels inside `bounds` (pixels of the area they are drawn on).
    pub(crate) fn new(bounds: Rect) -> Self {
        LabelPlacer {
            bounds,
            taken: Vec::new(),
        }
    }

    /// Marks a region (a marker) that labels must not cover.
    pub(crate) fn block(&mut self, rect: Rect) {
        self.taken.push(rect);
    }

    /// Draws the label beside its marker on the first of `sides` that is free; if none is
    /// and `force` is set, on the first side that stays inside the area (overlapping).
    /// Returns whether the label was drawn.
    pub(crate) fn place<DB: DrawingBackend>(
        &mut self,
        area: &DrawingArea<DB, Shift>,
        label: &Label<'_>,
        sides: &[Side],
        force: bool,
    ) -> Result<bool, PlotError> {
        if label.text.is_empty() {
            return Ok(false);
        }
        let (w, h) = area.estimate_text_size(label.text, label.style)?;
        let size = (w as i32, h as i32);
        let candidates: Vec<(Pos, (i32, i32), Rect)> = sides
            .iter()
            .map(|side| {
                let (pos, point) = side.anchor(label.at, label.gap);
                (pos, point, text_box(pos, point, size))
            })
            .collect();
        let free = candidates.iter().find(|(_, _, rect)| {
            rect.inside(&self.bounds) && !self.taken.iter().any(|t| t.overlaps(rect))
        });
        let chosen = match free {
            Some(candidate) => Some(candidate),
            None if force => candidates
                .iter()
                .find(|(_, _, rect)| rect.inside(&self.bounds))
                .or(candidates.first()),
            None => None,
        };
        match chosen {
            Some((pos, point, rect)) => {
                area.draw_text(label.text, &label.style.pos(*pos), *point)?;
                self.taken.push(*rect);
                Ok(true)
            }
            None => Ok(false),
        }
    }
}

/// A label to place: its text and style, the marker's position (pixels) and the distance
/// to keep from it.
pub(crate) struct Label<'a> {
    pub(crate) text: &'a str,
    pub(crate) style: &'a TextStyle<'a>,
    pub(crate) at: (i32, i32),
    pub(crate) gap: i32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_follow_the_anchor() {
        let rect = text_box(Pos::new(HPos::Right, VPos::Center), (100, 50), (40, 10));
        assert_eq!(
            rect,
            Rect {
                x0: 60,
                y0: 45,
                x1: 100,
                y1: 55
            }
        );
        assert!(rect.overlaps(&Rect::around((95, 50), 2)));
        assert!(!rect.overlaps(&Rect::around((110, 50), 2)));
        // Touching edges do not overlap.
        assert!(!rect.overlaps(&Rect {
            x0: 100,
            y0: 45,
            x1: 120,
            y1: 55
        }));
    }
}
