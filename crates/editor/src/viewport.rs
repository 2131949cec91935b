//! Pan and zoom: the map from image pixels to screen points. The model stays in image
//! space; only drawing and pointer input go through this map.

use egui::{Pos2, Rect, Vec2};
use glam::DVec2;

/// Zoom limits, screen points per image pixel.
const MIN_ZOOM: f32 = 0.01;
const MAX_ZOOM: f32 = 64.0;

/// `screen = origin + zoom · image`, with `origin` relative to the canvas' top-left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Screen points per image pixel.
    pub zoom: f32,
    /// Where image pixel (0, 0) is, relative to the canvas' top-left corner.
    pub origin: Vec2,
    /// The canvas on screen (set every frame).
    pub canvas: Rect,
}

impl Default for Viewport {
    fn default() -> Self {
        Self {
            zoom: 1.0,
            origin: Vec2::ZERO,
            canvas: Rect::from_min_size(Pos2::ZERO, Vec2::splat(1.0)),
        }
    }
}

impl Viewport {
    /// Image pixels to screen points.
    pub fn to_screen(&self, p: DVec2) -> Pos2 {
        self.canvas.min + self.origin + Vec2::new(p.x as f32, p.y as f32) * self.zoom
    }

    /// Screen points to image pixels.
    pub fn to_image(&self, p: Pos2) -> DVec2 {
        let v = (p - self.canvas.min - self.origin) / self.zoom;
        DVec2::new(f64::from(v.x), f64::from(v.y))
    }

    /// Centres an image of `size` pixels in the canvas, as large as fits with a margin.
    pub fn fit(&mut self, size: [u32; 2]) {
        let (w, h) = (size[0].max(1) as f32, size[1].max(1) as f32);
        let room = (self.canvas.size() - Vec2::splat(32.0)).max(Vec2::splat(16.0));
        self.zoom = (room.x / w).min(room.y / h).clamp(MIN_ZOOM, MAX_ZOOM);
        self.origin = (self.canvas.size() - Vec2::new(w, h) * self.zoom) * 0.5;
    }

    /// Multiplies the zoom by `factor`, keeping the image point under `pivot` (screen)
    /// where it is.
    pub fn zoom_about(&mut self, pivot: Pos2, factor: f32) {
        let anchor = self.to_image(pivot);
        self.zoom = (self.zoom * factor).clamp(MIN_ZOOM, MAX_ZOOM);
        let moved = self.to_screen(anchor);
        self.origin += pivot - moved;
    }

    /// The image-to-device-coordinates map of a paint callback covering the canvas.
    pub fn device_map(&self) -> ([f32; 2], [f32; 2]) {
        let size = self.canvas.size().max(Vec2::splat(1.0));
        (
            [2.0 * self.zoom / size.x, -2.0 * self.zoom / size.y],
            [
                2.0 * self.origin.x / size.x - 1.0,
                1.0 - 2.0 * self.origin.y / size.y,
            ],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn viewport() -> Viewport {
        Viewport {
            canvas: Rect::from_min_size(Pos2::new(100.0, 50.0), Vec2::new(800.0, 600.0)),
            ..Viewport::default()
        }
    }

    #[test]
    fn screen_and_image_round_trip() {
        let mut v = viewport();
        v.fit([400, 200]);
        let p = DVec2::new(123.0, 45.0);
        assert!((v.to_image(v.to_screen(p)) - p).length() < 1e-3);
        assert!(v.canvas.contains(v.to_screen(DVec2::ZERO)));
        assert!(v.canvas.contains(v.to_screen(DVec2::new(400.0, 200.0))));
    }

    #[test]
    fn zoom_keeps_the_pivot() {
        let mut v = viewport();
        v.fit([400, 200]);
        let pivot = Pos2::new(300.0, 260.0);
        let under = v.to_image(pivot);
        v.zoom_about(pivot, 3.0);
        assert!((v.to_image(pivot) - under).length() < 1e-3);
        v.zoom_about(pivot, 1e9);
        assert_eq!(v.zoom, MAX_ZOOM);
    }

    #[test]
    fn device_map_sends_the_canvas_corners_to_the_unit_square() {
        let v = viewport();
        let (scale, offset) = v.device_map();
        let corner = |p: Pos2| {
            let i = v.to_image(p);
            [
                i.x as f32 * scale[0] + offset[0],
                i.y as f32 * scale[1] + offset[1],
            ]
        };
        let tl = corner(v.canvas.min);
        let br = corner(v.canvas.max);
        assert!(
            (tl[0] + 1.0).abs() < 1e-5 && (tl[1] - 1.0).abs() < 1e-5,
            "{tl:?}"
        );
        assert!(
            (br[0] - 1.0).abs() < 1e-5 && (br[1] + 1.0).abs() < 1e-5,
            "{br:?}"
        );
    }
}
