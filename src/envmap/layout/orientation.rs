//! How a map's own directions relate to the world's: its up axis and a turn about it.

/// Which world axis is up in a map's own space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Up {
    /// Y up (OpenEXR, the world here).
    #[default]
    Y,
    /// Z up (Blender and most DCC tools); map +Z becomes world +Y, map +Y becomes world −Z.
    Z,
}

/// How a map's own directions relate to the world (OpenEXR's, Y up): first the up axis is made
/// Y, then the map is turned by `rotation_deg` about the (world) up axis, counter-clockwise seen
/// from above (+Z towards +X).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orientation {
    /// The map's up axis.
    pub up: Up,
    /// Rotation about the up axis, degrees.
    pub rotation_deg: f64,
}

impl Default for Orientation {
    fn default() -> Self {
        Orientation {
            up: Up::Y,
            rotation_deg: 0.0,
        }
    }
}

impl Orientation {
    /// A map-space direction in world space.
    pub fn to_world(&self, d: [f64; 3]) -> [f64; 3] {
        let [x, y, z] = match self.up {
            Up::Y => d,
            Up::Z => [d[0], d[2], -d[1]],
        };
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        [c * x + s * z, y, -s * x + c * z]
    }

    /// Whether this is the identity (OpenEXR's own orientation).
    pub fn is_identity(&self) -> bool {
        self.up == Up::Y && self.rotation_deg.rem_euclid(360.0) == 0.0
    }

    /// [`Orientation::to_map`] as a matrix (rows), for use per sample.
    pub fn to_map_matrix(&self) -> [[f64; 3]; 3] {
        let col = |d: [f64; 3]| self.to_map(d);
        let (x, y, z) = (
            col([1.0, 0.0, 0.0]),
            col([0.0, 1.0, 0.0]),
            col([0.0, 0.0, 1.0]),
        );
        [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    }

    /// A world-space direction in map space (the inverse of [`Orientation::to_world`]).
    pub fn to_map(&self, d: [f64; 3]) -> [f64; 3] {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        let [x, y, z] = [c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]];
        match self.up {
            Up::Y => [x, y, z],
            Up::Z => [x, -z, y],
        }
    }
}
