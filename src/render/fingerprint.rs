//! A scene's fingerprint: a BLAKE3 hash of everything in it (its size, view, orientation,
//! lightings with their spectra and maps, objects and backdrop), the part of a cached
//! quadrature's key ([`crate::quadrature::cache::Key`]) that the scene decides.
//!
//! The scene is hashed as its `Debug` text (Rust writes every `f64` so that it reads back
//! exactly), with each map's texels hashed as their bytes instead of as text.

use super::{Environment, Scene};

impl Scene {
    /// The hash of the whole scene (see the module docs).
    pub fn fingerprint(&self) -> [u8; 32] {
        let mut h = blake3::Hasher::new();
        let mut plain = self.clone();
        for (i, l) in plain.lightings.iter_mut().enumerate() {
            if let Environment::Map(maps) = &l.environment {
                for m in [&maps.light, &maps.seen] {
                    h.update(
                        format!("map {i}: {}x{}x{}\n", m.width, m.height, m.groups).as_bytes(),
                    );
                    h.update(bytemuck::cast_slice(&m.texels));
                }
                // Hashed above; its text would be the texels again.
                l.environment = Environment::Uniform { radiance: f64::NAN };
            }
        }
        h.update(format!("{plain:?}").as_bytes());
        *h.finalize().as_bytes()
    }
}

#[cfg(test)]
mod tests {
    use crate::render::env::{CoeffMap, Maps};
    use crate::render::{Environment, Preset};
    use std::sync::Arc;

    #[test]
    fn whatever_changes_in_a_scene_changes_its_fingerprint() {
        let ball = || Preset::Ball.scene(64, 64, "D65", None).unwrap();
        let base = ball().fingerprint();
        assert_eq!(ball().fingerprint(), base);
        let mut other = ball();
        other.width = 65;
        assert_ne!(other.fingerprint(), base);
        let mut other = ball();
        other.objects[0].surface.kd += 1e-12;
        assert_ne!(other.fingerprint(), base);
        assert_ne!(
            Preset::Ball.scene(64, 64, "A", None).unwrap().fingerprint(),
            base
        );
        // A map's texels count, one by one.
        let map = |v: f32| {
            let mut m = CoeffMap::constant([0.5; 4]);
            m.texels[0][2] = v;
            Environment::Map(Arc::new(Maps {
                light: m.clone(),
                seen: m,
            }))
        };
        let with = |v: f32| {
            let mut s = ball();
            s.lightings[0].environment = map(v);
            s.fingerprint()
        };
        assert_eq!(with(0.25), with(0.25));
        assert_ne!(with(0.25), with(0.2500001));
        assert_ne!(with(0.25), base);
    }
}
