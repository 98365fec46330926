//! (ours) The three fixed views of a picture (front, side, top) chosen from the surface's up
//! axis, and the orthographic projection that fits the mesh's bounding box in a tile.

use glam::DVec3;

/// A world axis (the surface's up direction).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// `x`, `y` or `z`.
    pub fn parse(s: &str) -> Option<Axis> {
        match s.trim().to_ascii_lowercase().as_str() {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "z" => Some(Axis::Z),
            _ => None,
        }
    }

    /// The unit vector.
    pub fn unit(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }

    /// The letter.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
        }
    }
}

/// An orthographic view: screen right, screen up, and the direction toward the viewer
/// (`right x up = toward`, a right-handed frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// `front`, `side` or `top`, with the axis looked along (e.g. `front (from -y)`).
    pub name: &'static str,
    pub right: DVec3,
    pub up: DVec3,
    pub toward: DVec3,
}

impl View {
    /// Screen coordinates (right, up) and depth (larger is nearer the viewer).
    pub fn project(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.right), p.dot(self.up), p.dot(self.toward))
    }
}

/// Front, side and top views of a surface whose up axis is `up`: front and side keep `up`
/// pointing up the screen, the top view looks down it.
pub fn views(up: Axis) -> [View; 3] {
    // `right` of the front view; the viewer stands at `right x up`.
    let (right, names) = match up {
        Axis::Z => (
            DVec3::X,
            ["front (from -y)", "side (from +x)", "top (from +z)"],
        ),
        Axis::Y => (
            DVec3::X,
            ["front (from +z)", "side (from +x)", "top (from +y)"],
        ),
        Axis::X => (
            DVec3::Y,
            ["front (from -z)", "side (from +y)", "top (from +x)"],
        ),
    };
    let u = up.unit();
    let toward = right.cross(u);
    let front = View {
        name: names[0],
        right,
        up: u,
        toward,
    };
    // Side: the viewer moves to the front view's right.
    let side = View {
        name: names[1],
        right: u.cross(right),
        up: u,
        toward: right,
    };
    // Top: looking down `up`, the front viewer's side at the bottom of the screen.
    let top = View {
        name: names[2],
        right,
        up: -toward,
        toward: u,
    };
    [front, side, top]
}

/// Maps a view's screen coordinates to the pixels of a `w x h` tile at `(x0, y0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub view: View,
    /// Pixels per surface unit.
    pub scale: f64,
    /// The screen point at the tile's centre.
    pub center: [f64; 2],
    pub origin: [f64; 2],
    pub size: [f64; 2],
}

impl Frame {
    /// The frame that shows `points` whole in the tile, with `margin` pixels on each side.
    pub fn fit(
        view: View,
        points: &[DVec3],
        origin: [u32; 2],
        size: [u32; 2],
        margin: f64,
    ) -> Frame {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in points {
            let q = view.project(*p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
        if !lo.is_finite() {
            (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        }
        let ext = (hi - lo).max(DVec3::splat(f64::MIN_POSITIVE));
        let avail = [
            (size[0] as f64 - 2.0 * margin).max(1.0),
            (size[1] as f64 - 2.0 * margin).max(1.0),
        ];
        let scale = (avail[0] / ext.x).min(avail[1] / ext.y);
        Frame {
            view,
            scale,
            center: [(lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0],
            origin: [origin[0] as f64, origin[1] as f64],
            size: [size[0] as f64, size[1] as f64],
        }
    }

    /// Pixel coordinates (x right, y down) and depth of a point.
    pub fn pixel(&self, p: DVec3) -> [f64; 3] {
        let q = self.view.project(p);
        [
            self.origin[0] + self.size[0] / 2.0 + (q.x - self.center[0]) * self.scale,
            self.origin[1] + self.size[1] / 2.0 - (q.y - self.center[1]) * self.scale,
            q.z,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_right_handed_and_keep_up() {
        for up in [Axis::X, Axis::Y, Axis::Z] {
            let v = views(up);
            for w in &v {
                assert_eq!(w.right.cross(w.up), w.toward, "{up:?} {}", w.name);
            }
            assert_eq!(v[0].up, up.unit());
            assert_eq!(v[1].up, up.unit());
            assert_eq!(v[2].toward, up.unit());
        }
    }

    #[test]
    fn fit_puts_the_box_inside_the_tile() {
        let pts = [DVec3::new(-2.0, 0.0, 5.0), DVec3::new(3.0, 1.0, 9.0)];
        for v in views(Axis::Z) {
            let f = Frame::fit(v, &pts, [100, 10], [200, 100], 5.0);
            for p in pts {
                let [x, y, _] = f.pixel(p);
                assert!(
                    (105.0..=295.0).contains(&x) && (15.0..=105.0).contains(&y),
                    "{x} {y}"
                );
            }
        }
    }
}
