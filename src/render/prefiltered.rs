//! The pre-filtered maps of a map lighting ([`super::env::prefilter`]), kept while the map
//! lives. A viewer prepares its scene again for every film, pigment or shininess it is shown,
//! and pre-filtering the map was most of that (176 ms of a 512x512 thickness drag's 460 ms on
//! lavapipe, against nothing that depends on the film). Keyed by the map's `Arc` (a map is
//! never changed once built) and the lobe; entries of maps no longer alive are dropped.

use super::latlong::{CoeffMap, Maps};
use std::sync::{Arc, Mutex, Weak};

/// Which filtered map: the diffuse one, or the specular one of a shininess (its bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Lobe {
    Diffuse,
    Specular(u64),
}

struct Entry {
    maps: Weak<Maps>,
    lobe: Lobe,
    map: CoeffMap,
}

/// At most this many filtered maps are kept (a few maps, a few shininesses).
const KEPT: usize = 16;

static MEMO: Mutex<Vec<Entry>> = Mutex::new(Vec::new());

/// `maps`' filtered map for `lobe`: kept from an earlier call, or made by `make` (outside the
/// lock, so that two threads filtering different maps do not wait on each other) and kept.
pub(super) fn get_or_make(
    maps: &Arc<Maps>,
    lobe: Lobe,
    make: impl FnOnce() -> CoeffMap,
) -> CoeffMap {
    let weak = Arc::downgrade(maps);
    if let Ok(mut memo) = MEMO.lock() {
        memo.retain(|e| e.maps.strong_count() > 0);
        if let Some(e) = memo
            .iter()
            .find(|e| e.lobe == lobe && Weak::ptr_eq(&e.maps, &weak))
        {
            return e.map.clone();
        }
    }
    let map = make();
    if let Ok(mut memo) = MEMO.lock() {
        if memo.len() >= KEPT {
            memo.remove(0);
        }
        memo.push(Entry {
            maps: weak,
            lobe,
            map: map.clone(),
        });
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_is_filtered_once_while_it_lives() {
        let m = CoeffMap::from_fn(8, |d| [d[1].max(0.0) as f32, 0.0, 0.0, 1.0]);
        let maps = Arc::new(Maps {
            light: m.clone(),
            seen: m,
        });
        let mut made = 0;
        let mut get = |lobe| {
            get_or_make(&maps, lobe, || {
                made += 1;
                CoeffMap::constant([made as f32, 0.0, 0.0, 0.0])
            })
        };
        let a = get(Lobe::Diffuse);
        let b = get(Lobe::Diffuse);
        let c = get(Lobe::Specular(100f64.to_bits()));
        assert_eq!(a.texels, b.texels);
        assert_ne!(a.texels, c.texels);
        assert_eq!(made, 2);
        // Another map (even an equal one) is filtered for itself.
        let other = Arc::new(Maps {
            light: maps.light.clone(),
            seen: maps.seen.clone(),
        });
        let d = get_or_make(&other, Lobe::Diffuse, || {
            CoeffMap::constant([9.0, 0.0, 0.0, 0.0])
        });
        assert_eq!(d.texels[0][0], 9.0);
    }
}
