//! Which texels of a lighting's seen map (the map shown behind the objects, the sun's disc in
//! it) the image can show: the texels the renderer reads for the background of some pixel,
//! behind the objects where the lighting is the background's, or through a transparent object
//! it lights. A texel the image never shows adds nothing to the image's error. Yet it would
//! drive the fit if it were among the texels it checks. The ball under the sunrise photograph
//! errs 1.1 on the sun's disc at 7 nodes, but the camera looks away from the sun.

use crate::render::cpu::pinhole_direction;
use crate::render::env::{bilinear, CoeffMap};
use crate::render::prepare::pinhole_tangent;
use crate::render::{Backdrop, Environment, Scene};

impl Scene {
    /// [`Scene::visible_seen`] of every lighting, in order: what a choice of quadrature reads
    /// for each of its rounds.
    pub(super) fn visible_seens(&self) -> Vec<Option<CoeffMap>> {
        (0..self.lightings.len())
            .map(|li| self.visible_seen(li))
            .collect()
    }

    /// Lighting `li`'s seen map with every texel the image cannot show set to zero (None when
    /// the lighting is not a map).
    pub(super) fn visible_seen(&self, li: usize) -> Option<CoeffMap> {
        let Environment::Map(maps) = &self.lightings[li].environment else {
            return None;
        };
        let seen = &maps.seen;
        let mut shown = vec![false; seen.width * seen.height];
        if self.any_orientation {
            // Every orientation: the camera may look anywhere.
            return Some(seen.clone());
        }
        let behind = li == self.background && self.backdrop != Backdrop::Hidden;
        let through = self
            .objects
            .iter()
            .any(|o| o.lighting == li && o.surface.transparent);
        if behind || through {
            let t = pinhole_tangent(self.backdrop) as f64;
            for y in 0..self.height {
                for x in 0..self.width {
                    let d = pinhole_direction(t, self.width, self.height, x, y);
                    let d = crate::render::rotate(&self.orientation, d);
                    for (i, w) in bilinear(seen.width, seen.height, d) {
                        if w > 0.0 {
                            shown[i] = true;
                        }
                    }
                }
            }
        }
        let mut out = seen.clone();
        for (i, shown) in shown.iter().enumerate() {
            if !shown {
                out.texels[i * seen.groups..(i + 1) * seen.groups].fill([0.0; 4]);
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use crate::render::env::{self, CoeffMap};
    use crate::render::{Backdrop, Preset};

    #[test]
    fn only_the_texels_behind_the_view_are_shown() {
        // A map whose every texel is lit: through the default 60 degree pinhole down -Z, the
        // image shows a patch around -Z and nothing near +Z (behind the camera).
        let map = CoeffMap::from_fn(64, |_| [1.0, 0.0, 0.0, 0.0]);
        let maps = env::Maps {
            light: map.clone(),
            seen: map.clone(),
        };
        let l = super::super::expansion::tests::paper_lighting("D65", maps);
        let mut scene = Preset::Ball.scene(24, 24, "D65", Some(l)).unwrap();
        let lit = |s: &crate::render::Scene| -> Vec<[f64; 3]> {
            let v = s.visible_seen(s.background).unwrap();
            (0..v.width * v.height)
                .filter(|&i| v.texels[i][0] > 0.0)
                .map(|i| env::direction(v.width, v.height, i % v.width, i / v.width))
                .collect()
        };
        let shown = lit(&scene);
        assert!(!shown.is_empty() && shown.len() < map.texels.len() / 4);
        // Every shown texel lies within the field of view's corner angle of -Z (plus a texel).
        let corner = (30f64.to_radians().tan() * 2f64.sqrt()).atan().to_degrees();
        let texel = 180.0 / 64.0;
        for d in &shown {
            let off = (-d[2]).clamp(-1.0, 1.0).acos().to_degrees();
            assert!(off <= corner + 2.0 * texel, "{d:?} {off}");
        }
        // Hidden: the ball is not transparent, so nothing is shown.
        scene.backdrop = Backdrop::Hidden;
        assert!(lit(&scene).is_empty());
    }
}
