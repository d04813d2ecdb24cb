//! Cube faces and where each cube-like layout puts them: the cells and the directions their
//! images' right and down point to.

/// A cube face, named by the axis its centre looks down.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// +X
    PosX,
    /// −X
    NegX,
    /// +Y (up)
    PosY,
    /// −Y (down)
    NegY,
    /// +Z
    PosZ,
    /// −Z
    NegZ,
}

impl Face {
    /// The six faces in OpenEXR's order.
    pub const ALL: [Face; 6] = [
        Face::PosX,
        Face::NegX,
        Face::PosY,
        Face::NegY,
        Face::PosZ,
        Face::NegZ,
    ];

    /// "+X", "-X", "+Y", "-Y", "+Z" or "-Z".
    pub fn name(self) -> &'static str {
        match self {
            Face::PosX => "+X",
            Face::NegX => "-X",
            Face::PosY => "+Y",
            Face::NegY => "-Y",
            Face::PosZ => "+Z",
            Face::NegZ => "-Z",
        }
    }

    /// The unit vector the face's centre looks down.
    pub fn axis(self) -> [f64; 3] {
        match self {
            Face::PosX => [1.0, 0.0, 0.0],
            Face::NegX => [-1.0, 0.0, 0.0],
            Face::PosY => [0.0, 1.0, 0.0],
            Face::NegY => [0.0, -1.0, 0.0],
            Face::PosZ => [0.0, 0.0, 1.0],
            Face::NegZ => [0.0, 0.0, -1.0],
        }
    }

    /// The face a direction falls on, with OpenEXR's tie-breaking
    /// (`CubeMap::faceAndPixelPosition`: X before Y before Z).
    pub fn of(dir: [f64; 3]) -> Face {
        let [x, y, z] = dir;
        let (ax, ay, az) = (x.abs(), y.abs(), z.abs());
        if ax >= ay && ax >= az {
            if x > 0.0 || ax == 0.0 {
                Face::PosX
            } else {
                Face::NegX
            }
        } else if ay >= az {
            if y > 0.0 {
                Face::PosY
            } else {
                Face::NegY
            }
        } else if z > 0.0 {
            Face::PosZ
        } else {
            Face::NegZ
        }
    }

    /// The face's position in [`Face::ALL`].
    pub(super) fn index(self) -> usize {
        self as usize
    }
}

/// One face's cell in a cube-like layout: where it is (in face-size units) and which world
/// directions its image's right and down point to.
#[derive(Debug, Clone, Copy)]
pub(super) struct Slot {
    pub(super) col: usize,
    pub(super) row: usize,
    pub(super) right: [f64; 3],
    pub(super) down: [f64; 3],
}

const PX: [f64; 3] = [1.0, 0.0, 0.0];
const NX: [f64; 3] = [-1.0, 0.0, 0.0];
const PY: [f64; 3] = [0.0, 1.0, 0.0];
const NY: [f64; 3] = [0.0, -1.0, 0.0];
const PZ: [f64; 3] = [0.0, 0.0, 1.0];
const NZ: [f64; 3] = [0.0, 0.0, -1.0];

/// A slot at cell (col, row) whose image's right and down point to `right` and `down`.
const fn slot(col: usize, row: usize, right: [f64; 3], down: [f64; 3]) -> Slot {
    Slot {
        col,
        row,
        right,
        down,
    }
}

/// OpenEXR's cube: `CubeMap::pixelPosition` read as "right / down go towards".
pub(super) const CUBE: [Slot; 6] = [
    slot(0, 0, PZ, NY),
    slot(0, 1, NZ, NY),
    slot(0, 2, PX, NZ),
    slot(0, 3, PX, PZ),
    slot(0, 4, NX, NY),
    slot(0, 5, PX, NY),
];
/// Horizontal cross: middle row −X, −Z, +X, +Z; +Y above and −Y below −Z; OpenEXR's faces.
pub(super) const HCROSS: [Slot; 6] = [
    slot(2, 1, PZ, NY),
    slot(0, 1, NZ, NY),
    slot(1, 0, PX, NZ),
    slot(1, 2, PX, PZ),
    slot(3, 1, NX, NY),
    slot(1, 1, PX, NY),
];
/// Vertical cross: as the horizontal one, with +Z below −Y, turned 180°.
pub(super) const VCROSS: [Slot; 6] = {
    let mut v = HCROSS;
    v[4] = slot(1, 3, PX, PY);
    v
};
/// Horizontal strip: OpenEXR's faces side by side, in its order, each as in the cube.
pub(super) const HSTRIP: [Slot; 6] = {
    let mut h = CUBE;
    let mut i = 0;
    while i < 6 {
        h[i].col = i;
        h[i].row = 0;
        i += 1;
    }
    h
};
/// Vertical strip: OpenEXR's cube.
pub(super) const VSTRIP: [Slot; 6] = CUBE;

/// The slot of the pixel (x, y) of a cube-like layout of face size n, with the pixel's position
/// inside the face.
pub(super) fn locate(
    slots: &[Slot; 6],
    n: usize,
    x: usize,
    y: usize,
) -> Option<(Face, &Slot, usize, usize)> {
    let (col, row) = (x / n, y / n);
    Face::ALL
        .iter()
        .zip(slots.iter())
        .find(|(_, s)| s.col == col && s.row == row)
        .map(|(f, s)| (*f, s, x % n, y % n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_ties_follow_openexr() {
        // CubeMap::faceAndPixelPosition: X wins ties with Y and Z, Y wins ties with Z.
        assert_eq!(Face::of([1.0, 1.0, 1.0]), Face::PosX);
        assert_eq!(Face::of([-1.0, -1.0, 0.0]), Face::NegX);
        assert_eq!(Face::of([0.0, 1.0, -1.0]), Face::PosY);
        assert_eq!(Face::of([0.0, 0.0, -1.0]), Face::NegZ);
        assert_eq!(Face::of([0.0, 0.0, 0.0]), Face::PosX);
        let names: Vec<_> = Face::ALL.iter().map(|f| f.name()).collect();
        assert_eq!(names, ["+X", "-X", "+Y", "-Y", "+Z", "-Z"]);
    }
}
