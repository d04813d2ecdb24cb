//! Thin-film optics against closed forms, at the extremes the issue lists (normal and grazing
//! incidence, total internal reflection, zero and 1 mm thickness, absorbing films, metals, f32).

use specmap::spectrum::WavelengthGrid;
use specmap::thinfilm::{
    Coherence, Film, Incidence, Index, Layer, Material, Polarization, Stack, Wave,
};

/// Layers as (index, thickness in nm) from the ambient side.
type Layers = Vec<(Index, f64)>;

fn idx(n: f64, k: f64) -> Index {
    Index::new(n, k).unwrap()
}

fn deg(a: f64) -> Incidence {
    Incidence::degrees(a).unwrap()
}

fn film(lambda: f64, ambient: f64, layers: &[(Index, f64)], substrate: Index) -> Film<f64> {
    Film::new(lambda, idx(ambient, 0.0), layers, substrate).unwrap()
}

fn rt(f: &Film<f64>, a: f64, pol: Polarization) -> (f64, f64) {
    let r = f.rt(&deg(a), pol);
    (r.r, r.t)
}

const POLS: [Polarization; 3] = [Polarization::S, Polarization::P, Polarization::Unpolarized];
const ANGLES: [f64; 8] = [0.0, 10.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.9];

/// Textbook Fresnel power coefficients between transparent media, with real angles (Born & Wolf).
fn fresnel_real(n1: f64, n2: f64, deg: f64) -> [(f64, f64); 2] {
    let t1 = deg.to_radians();
    let t2 = (n1 * t1.sin() / n2).asin();
    let (c1, c2) = (t1.cos(), t2.cos());
    let rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2);
    let rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
    let ts = 2.0 * n1 * c1 / (n1 * c1 + n2 * c2);
    let tp = 2.0 * n1 * c1 / (n2 * c1 + n1 * c2);
    let k = n2 * c2 / (n1 * c1);
    [(rs * rs, k * ts * ts), (rp * rp, k * tp * tp)]
}

#[test]
fn single_interface_is_fresnel() {
    for (n1, n2) in [(1.0, 1.5), (1.0, 2.7), (1.33, 1.0), (1.5, 1.0)] {
        let f = film(550.0, n1, &[], idx(n2, 0.0));
        for a in ANGLES {
            if n1 > n2 && a >= (n2 / n1).asin().to_degrees() {
                continue; // TIR: own test
            }
            let [s, p] = fresnel_real(n1, n2, a);
            let (rs, ts) = rt(&f, a, Polarization::S);
            let (rp, tp) = rt(&f, a, Polarization::P);
            assert!(
                (rs - s.0).abs() < 1e-13,
                "{n1}->{n2} at {a}: Rs {rs} vs {}",
                s.0
            );
            assert!(
                (ts - s.1).abs() < 1e-12,
                "{n1}->{n2} at {a}: Ts {ts} vs {}",
                s.1
            );
            assert!(
                (rp - p.0).abs() < 1e-13,
                "{n1}->{n2} at {a}: Rp {rp} vs {}",
                p.0
            );
            assert!(
                (tp - p.1).abs() < 1e-12,
                "{n1}->{n2} at {a}: Tp {tp} vs {}",
                p.1
            );
        }
    }
    // Brewster's angle: Rp = 0.
    let f = film(550.0, 1.0, &[], idx(1.5, 0.0));
    let brewster = 1.5f64.atan().to_degrees();
    assert!(f.rt(&deg(brewster), Polarization::P).r < 1e-30);
}

#[test]
fn metal_at_normal_incidence_is_the_closed_form() {
    // R = ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) into an absorbing half-space.
    for (n, k) in [(3.1, 3.3), (0.05, 3.0), (1.5, 0.1), (0.0, 2.0)] {
        let f = film(500.0, 1.0, &[], idx(n, k));
        let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        for pol in POLS {
            let (r, t) = rt(&f, 0.0, pol);
            assert!((r - want).abs() < 1e-14, "{n}+{k}i {pol}: {r} vs {want}");
            // Nothing is absorbed before the substrate: all the rest enters it.
            assert!((r + t - 1.0).abs() < 1e-14);
        }
    }
}

/// Paper Eq. 7 for a transparent film at normal incidence, in real arithmetic:
/// R = (r01^2 + r12^2 + 2 r01 r12 cos 2d) / (1 + r01^2 r12^2 + 2 r01 r12 cos 2d).
fn single_film_normal(n0: f64, n1: f64, n2: f64, d: f64, lambda: f64) -> f64 {
    let r01 = (n0 - n1) / (n0 + n1);
    let r12 = (n1 - n2) / (n1 + n2);
    let c = (4.0 * std::f64::consts::PI * n1 * d / lambda).cos();
    (r01 * r01 + r12 * r12 + 2.0 * r01 * r12 * c)
        / (1.0 + r01 * r01 * r12 * r12 + 2.0 * r01 * r12 * c)
}

#[test]
fn single_film_is_the_airy_closed_form() {
    // The paper's films: chrome oxide 270 nm n = 2.7 and TiO2 150/350 nm n = 2.3 on 1.45.
    for (n1, d) in [(2.7, 270.0), (2.3, 150.0), (2.3, 350.0), (1.33, 400.0)] {
        for lambda in [380.0, 455.5, 550.0, 633.0, 780.0] {
            let f = film(lambda, 1.0, &[(idx(n1, 0.0), d)], idx(1.45, 0.0));
            let want = single_film_normal(1.0, n1, 1.45, d, lambda);
            for pol in POLS {
                let (r, t) = rt(&f, 0.0, pol);
                assert!(
                    (r - want).abs() < 1e-14,
                    "{n1} {d} nm at {lambda}: {r} vs {want}"
                );
                assert!((r + t - 1.0).abs() < 1e-14, "lossless: R + T = 1");
            }
        }
    }
}

#[test]
fn quarter_wave_antireflection_gives_zero_at_the_design_wavelength() {
    let (n0, ns, lambda) = (1.0f64, 1.52, 550.0);
    let nf = (n0 * ns).sqrt();
    let f = film(
        lambda,
        n0,
        &[(idx(nf, 0.0), lambda / (4.0 * nf))],
        idx(ns, 0.0),
    );
    for pol in POLS {
        let (r, t) = rt(&f, 0.0, pol);
        assert!(r < 1e-30, "{pol}: R = {r}");
        assert!((t - 1.0).abs() < 1e-14);
    }
    // And not at other wavelengths.
    let off = film(
        450.0,
        n0,
        &[(idx(nf, 0.0), lambda / (4.0 * nf))],
        idx(ns, 0.0),
    );
    assert!(off.rt(&Incidence::NORMAL, Polarization::S).r > 1e-4);
}

#[test]
fn normal_incidence_makes_s_and_p_equal() {
    let layers = [
        (idx(2.3, 0.0), 150.0),
        (idx(1.38, 0.0), 100.0),
        (idx(1.6, 0.2), 60.0),
    ];
    let f = film(500.0, 1.0, &layers, idx(3.1, 3.3));
    let s = f.rt(&Incidence::NORMAL, Polarization::S);
    let p = f.rt(&Incidence::NORMAL, Polarization::P);
    assert!((s.r - p.r).abs() < 1e-15 && (s.t - p.t).abs() < 1e-15);
}

#[test]
fn grazing_incidence_reflects_everything() {
    let stacks: Vec<(f64, Layers, Index)> = vec![
        (1.0, vec![], idx(1.5, 0.0)),
        (1.0, vec![(idx(2.7, 0.0), 270.0)], idx(1.45, 0.0)),
        (1.0, vec![(idx(1.0, 0.0), 100.0)], idx(1.0, 0.0)), // no interface at all
        (1.5, vec![(idx(1.0, 0.0), 50.0)], idx(1.5, 0.0)),
        (1.0, vec![(idx(2.0, 0.5), 80.0)], idx(3.1, 3.3)),
    ];
    for (n0, layers, sub) in &stacks {
        let f = film(550.0, *n0, layers, *sub);
        for pol in POLS {
            let (r, t) = rt(&f, 90.0, pol);
            assert_eq!((r, t), (1.0, 0.0), "{layers:?} {pol}");
            // The limit from below is continuous (for stacks with an interface).
            if layers.len() != 1 || layers[0].0 != idx(1.0, 0.0) {
                let (r, t) = rt(&f, 89.9999, pol);
                assert!(r > 0.999 && r <= 1.0 + 1e-12 && t.is_finite(), "{r} {t}");
            }
        }
    }
}

#[test]
fn total_internal_reflection() {
    // Glass into air beyond the critical angle (41.8 degrees): R = 1, T = 0, for s and p, also
    // with transparent films in between.
    for layers in [
        vec![],
        vec![(idx(2.3, 0.0), 150.0)],
        vec![(idx(1.38, 0.0), 90.0), (idx(2.0, 0.0), 60.0)],
    ] {
        let f = film(550.0, 1.5, &layers, idx(1.0, 0.0));
        for a in [42.0, 45.0, 60.0, 89.9, 90.0] {
            for pol in POLS {
                let (r, t) = rt(&f, a, pol);
                assert!((r - 1.0).abs() < 1e-13, "{a} {pol}: R = {r}");
                assert_eq!(t, 0.0);
            }
        }
    }
}

#[test]
fn frustrated_total_internal_reflection_matches_the_tunnelling_formula() {
    // Glass | air gap d | glass at 60 degrees (beyond the critical angle): the gap is evanescent,
    // q = i beta. For s: 1/T = 1 + ((q1^2 + beta^2) / (2 q1 beta))^2 sinh^2(2 pi beta d / lambda);
    // for p the same with q1 -> q1 / n1^2 and beta -> beta / n2^2.
    let (n1, n2, lambda, a) = (1.5f64, 1.0f64, 550.0, 60.0f64);
    let xi = n1 * a.to_radians().sin();
    let q1 = n1 * a.to_radians().cos();
    let beta = (xi * xi - n2 * n2).sqrt();
    for d in [0.0, 10.0, 50.0, 100.0, 300.0, 1000.0, 5000.0] {
        let f = film(lambda, n1, &[(idx(n2, 0.0), d)], idx(n1, 0.0));
        let sh = (2.0 * std::f64::consts::PI * beta * d / lambda).sinh();
        for (pol, u, v) in [
            (Polarization::S, q1, beta),
            (Polarization::P, q1 / (n1 * n1), beta / (n2 * n2)),
        ] {
            let want_t = 1.0 / (1.0 + ((u * u + v * v) / (2.0 * u * v)).powi(2) * sh * sh);
            let (r, t) = rt(&f, a, pol);
            assert!(
                (t - want_t).abs() <= 1e-12 * want_t.max(1e-300) + 1e-300,
                "{d} nm {pol}: T {t} vs {want_t}"
            );
            assert!((r + t - 1.0).abs() < 1e-13);
        }
    }
}

#[test]
fn zero_thickness_is_the_bare_interface() {
    for film_n in [idx(2.7, 0.0), idx(1.6, 0.4), idx(0.2, 3.0)] {
        for sub in [idx(1.45, 0.0), idx(3.1, 3.3)] {
            let with = film(500.0, 1.0, &[(film_n, 0.0)], sub);
            let bare = film(500.0, 1.0, &[], sub);
            for a in ANGLES {
                for pol in POLS {
                    let (r1, t1) = rt(&with, a, pol);
                    let (r0, t0) = rt(&bare, a, pol);
                    assert!(
                        (r1 - r0).abs() < 1e-13 && (t1 - t0).abs() < 1e-13,
                        "{film_n} {a} {pol}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_film_matching_the_ambient_or_the_substrate_vanishes() {
    let bare = film(600.0, 1.33, &[], idx(1.52, 0.0));
    let like_ambient = film(600.0, 1.33, &[(idx(1.33, 0.0), 321.0)], idx(1.52, 0.0));
    let like_substrate = film(600.0, 1.33, &[(idx(1.52, 0.0), 321.0)], idx(1.52, 0.0));
    for a in ANGLES {
        for pol in POLS {
            let (r0, t0) = rt(&bare, a, pol);
            for f in [&like_ambient, &like_substrate] {
                let (r, t) = rt(f, a, pol);
                assert!(
                    (r - r0).abs() < 1e-14 && (t - t0).abs() < 1e-13,
                    "{a} {pol}: {r} vs {r0}"
                );
            }
        }
    }
}

#[test]
fn absorbing_films_and_metal_substrates_conserve_energy() {
    let cases: Vec<(Layers, Index)> = vec![
        (vec![(idx(2.0, 0.5), 80.0)], idx(1.45, 0.0)),
        (vec![(idx(2.7, 0.3), 270.0)], idx(1.45, 0.0)),
        (vec![(idx(1.38, 0.0), 100.0)], idx(3.1, 3.3)),
        (
            vec![(idx(2.0, 0.1), 120.0), (idx(1.46, 0.0), 90.0)],
            idx(0.05, 3.0),
        ),
        (vec![(idx(0.2, 3.0), 30.0)], idx(1.52, 0.0)), // a thin metal film on glass
    ];
    for (layers, sub) in &cases {
        let absorbing_film = layers.iter().any(|(n, _)| n.k() > 0.0);
        let f = film(550.0, 1.0, layers, *sub);
        for a in ANGLES {
            for pol in POLS {
                let rt = f.rt(&deg(a), pol);
                let absorbed = rt.absorbed();
                assert!(
                    (0.0..=1.0).contains(&rt.r) && rt.t >= 0.0,
                    "{layers:?} {a}: {rt:?}"
                );
                if absorbing_film {
                    assert!(absorbed > 1e-6, "{layers:?} {a} {pol}: A = {absorbed}");
                    assert!(rt.t < 1.0 - rt.r);
                } else {
                    assert!(
                        absorbed.abs() < 1e-13,
                        "lossless layers absorb nothing: {absorbed}"
                    );
                }
            }
        }
    }
}

#[test]
fn absorbing_film_at_normal_incidence_matches_a_hand_computed_airy_sum() {
    // Single absorbing film at normal incidence: r and t from Eq. 4-7 written out with complex
    // numbers by hand (no Snell needed at 0 degrees), T = n_s |t|^2 / n_0.
    use nalgebra::Complex;
    let (n0, n1, ns, d, lambda) = (
        Complex::new(1.0, 0.0),
        Complex::new(2.0, 0.5),
        Complex::new(1.45, 0.0),
        80.0,
        550.0,
    );
    let r01 = (n0 - n1) / (n0 + n1);
    let r12 = (n1 - ns) / (n1 + ns);
    let t01 = n0 * 2.0 / (n0 + n1);
    let t12 = n1 * 2.0 / (n1 + ns);
    let e = (Complex::new(0.0, 2.0 * std::f64::consts::PI * d / lambda) * n1).exp();
    let den = Complex::new(1.0, 0.0) + r01 * r12 * e * e;
    let r = (r01 + r12 * e * e) / den;
    let t = t01 * t12 * e / den;
    let f = film(lambda, 1.0, &[(idx(2.0, 0.5), d)], idx(1.45, 0.0));
    let got = f.rt(&Incidence::NORMAL, Polarization::S);
    assert!((got.r - r.norm_sqr()).abs() < 1e-14);
    assert!((got.t - 1.45 * t.norm_sqr()).abs() < 1e-14);
    let (ra, ta) = f.amplitudes(&Incidence::NORMAL, Wave::S);
    assert!((ra - r).norm() < 1e-14 && (ta - t).norm() < 1e-14);
}

#[test]
fn millimetre_films_are_exact_when_coherent_and_incoherent_on_a_grid() {
    // Coherent at one wavelength: 1 mm of n = 1.5 is 6000 round-trip cycles at 500 nm, so the
    // film is a half-wave multiple (R = bare interface); + lambda / (4 n) makes it a quarter wave.
    let (n, ns, lambda) = (1.5, 2.25, 500.0);
    let half = film(lambda, 1.0, &[(idx(n, 0.0), 1e6)], idx(ns, 0.0));
    let bare = film(lambda, 1.0, &[], idx(ns, 0.0));
    let qw = 1e6 + lambda / (4.0 * n);
    let quarter = film(lambda, 1.0, &[(idx(n, 0.0), qw)], idx(ns, 0.0));
    let r_bare = bare.rt(&Incidence::NORMAL, Polarization::S).r;
    assert!((half.rt(&Incidence::NORMAL, Polarization::S).r - r_bare).abs() < 1e-12);
    // n = sqrt(1 * 2.25): the quarter wave is a perfect antireflection coating.
    assert!(quarter.rt(&Incidence::NORMAL, Polarization::S).r < 1e-12);
    // The same in f32, thanks to the range reduction: 2 pi * 6000 cycles in radians has an f32
    // ulp of 0.002 rad. An eighth-wave excess (a quarter cycle of round-trip phase), where R is
    // most sensitive to the phase, against the f64 closed form.
    let q32 = Film::<f32>::new(lambda, idx(1.0, 0.0), &[(idx(n, 0.0), qw)], idx(ns, 0.0)).unwrap();
    assert!(q32.rt(&Incidence::NORMAL, Polarization::S).r < 1e-6);
    let ew = 1e6 + lambda / (8.0 * n);
    let e32 = Film::<f32>::new(lambda, idx(1.0, 0.0), &[(idx(n, 0.0), ew)], idx(1.0, 0.0)).unwrap();
    let want = single_film_normal(1.0, n, 1.0, ew, lambda);
    let got = e32.rt(&Incidence::NORMAL, Polarization::S).r as f64;
    assert!((got - want).abs() < 2e-6, "f32 1 mm film: {got} vs {want}");

    // On a 1 nm grid the fringes (0.08 nm apart) are far finer than the step: the layer is
    // computed incoherently and flagged, and a free-standing slab then reflects
    // R = 2 R1 / (1 + R1), R1 = ((n - 1) / (n + 1))^2, at every wavelength.
    let stack = Stack::new(
        idx(1.0, 0.0).into(),
        vec![Layer::new(idx(n, 0.0).into(), 1e6).unwrap()],
        idx(1.0, 0.0).into(),
    );
    let grid = WavelengthGrid::visible_1nm();
    let r1 = ((n - 1.0) / (n + 1.0)).powi(2);
    for pol in POLS {
        let resp = stack
            .response(&grid, &Incidence::NORMAL, pol, Coherence::Auto)
            .unwrap();
        assert_eq!(resp.incoherent_layers, vec![0]);
        for (r, t) in resp.reflectance.iter().zip(&resp.transmittance) {
            assert!((r - 2.0 * r1 / (1.0 + r1)).abs() < 1e-14, "{r}");
            assert!((r + t - 1.0).abs() < 1e-14);
        }
        // Forced coherent: finite (aliased) values, never NaN.
        let coh = stack
            .response(&grid, &deg(45.0), pol, Coherence::Coherent)
            .unwrap();
        assert!(coh.incoherent_layers.is_empty());
        assert!(coh
            .reflectance
            .iter()
            .all(|r| r.is_finite() && (0.0..=1.0).contains(r)));
    }
    // A thin film on the same grid stays coherent.
    let thin = Stack::new(
        idx(1.0, 0.0).into(),
        vec![Layer::new(idx(2.7, 0.0).into(), 270.0).unwrap()],
        idx(1.45, 0.0).into(),
    );
    let resp = thin
        .response(&grid, &Incidence::NORMAL, Polarization::S, Coherence::Auto)
        .unwrap();
    assert!(resp.incoherent_layers.is_empty());
}

#[test]
fn thick_absorbing_slab_incoherent_closed_form() {
    // A thick weakly absorbing slab in air at normal incidence, incoherent:
    // R = R1 + (1 - R1)^2 R1 P^2 / (1 - R1^2 P^2), T = (1 - R1)^2 P / (1 - R1^2 P^2),
    // with P = exp(-4 pi k d / lambda) the single-pass transmission and R1 the interface
    // reflectance (k small enough that the interface is real to 1e-12... use exact complex R1).
    let (n, k, d, lambda) = (1.5, 1e-5, 1e5, 500.0);
    let stack = Stack::new(
        idx(1.0, 0.0).into(),
        vec![Layer::new(idx(n, k).into(), d).unwrap()],
        idx(1.0, 0.0).into(),
    );
    let grid = WavelengthGrid::new(lambda, lambda + 10.0, 1.0).unwrap();
    let resp = stack
        .response(&grid, &Incidence::NORMAL, Polarization::S, Coherence::Auto)
        .unwrap();
    assert_eq!(resp.incoherent_layers, vec![0]);
    let r1 = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
    // Power into the slab is 1 - R1 at the front; leaving through the back is (1 - R1) too
    // (tmm's T_from_t with Re(n) in the slab: n |t01 t10| ... equals 1 - R1 to O(k^2)).
    let p = (-4.0 * std::f64::consts::PI * k * d / lambda).exp();
    let want_r = r1 + (1.0 - r1).powi(2) * r1 * p * p / (1.0 - r1 * r1 * p * p);
    let want_t = (1.0 - r1).powi(2) * p / (1.0 - r1 * r1 * p * p);
    assert!(
        (resp.reflectance[0] - want_r).abs() < 1e-9,
        "{} vs {want_r}",
        resp.reflectance[0]
    );
    assert!(
        (resp.transmittance[0] - want_t).abs() < 1e-9,
        "{} vs {want_t}",
        resp.transmittance[0]
    );
    assert!(resp.transmittance[0] < 1.0 - resp.reflectance[0] - 0.02);
}

#[test]
fn f32_agrees_with_f64() {
    // Tolerance, absolute on R and T: 2e-6 up to 85 degrees (f32's unit roundoff is 6e-8; the
    // recursion amplifies it by a few tens), 1e-4 at 89.9 degrees, where cos theta_0 = 1.7e-3
    // and the Airy denominator 1 + r01 r12 e^{2i delta} cancels to about 2 cos theta_0 / n_1 at
    // a fringe maximum: an ill-conditioning of the problem in f32, not of the algorithm.
    let stacks: Vec<(f64, Layers, Index)> = vec![
        (1.0, vec![(idx(2.7, 0.0), 270.0)], idx(1.45, 0.0)),
        (1.0, vec![(idx(2.3, 0.0), 150.0)], idx(1.45, 0.0)),
        (1.0, vec![(idx(2.3, 0.0), 350.0)], idx(1.45, 0.0)),
        (1.0, vec![(idx(1.33, 0.0), 400.0)], idx(1.0, 0.0)),
        (
            1.0,
            vec![
                (idx(1.38, 0.0), 95.0),
                (idx(2.1, 0.0), 130.0),
                (idx(1.46, 0.0), 80.0),
            ],
            idx(1.52, 0.0),
        ),
        (1.0, vec![(idx(2.0, 0.3), 60.0)], idx(3.1, 3.3)),
        (1.5, vec![(idx(1.0, 0.0), 200.0)], idx(1.5, 0.0)), // FTIR beyond 41.8 degrees
    ];
    let mut worst = 0.0f64;
    let mut worst_grazing = 0.0f64;
    for (n0, layers, sub) in &stacks {
        for lambda in (380..=780).step_by(20) {
            let l = lambda as f64;
            let f64f = Film::<f64>::new(l, idx(*n0, 0.0), layers, *sub).unwrap();
            let f32f = Film::<f32>::new(l, idx(*n0, 0.0), layers, *sub).unwrap();
            for a in [0.0, 30.0, 60.0, 85.0, 89.9, 90.0] {
                for pol in POLS {
                    let x = f64f.rt(&deg(a), pol);
                    let y = f32f.rt(&deg(a), pol);
                    let e = (x.r - y.r as f64).abs().max((x.t - y.t as f64).abs());
                    if a <= 85.0 {
                        worst = worst.max(e);
                    } else {
                        worst_grazing = worst_grazing.max(e);
                    }
                }
            }
        }
    }
    assert!(
        worst < 2e-6,
        "worst |f32 - f64| up to 85 degrees = {worst:e}"
    );
    assert!(
        worst_grazing < 1e-4,
        "worst |f32 - f64| at 89.9-90 degrees = {worst_grazing:e}"
    );
}

#[test]
fn dispersion_formulas() {
    // N-BK7 at the helium d line (587.56 nm): nd = 1.5168 (Schott); fused silica 1.4585.
    let bk7 = Material::named("bk7").unwrap().index_at(587.56).unwrap();
    assert!((bk7.n() - 1.5168).abs() < 5e-5, "{}", bk7.n());
    let silica = Material::named("fused-silica")
        .unwrap()
        .index_at(587.6)
        .unwrap();
    assert!((silica.n() - 1.4585).abs() < 5e-5, "{}", silica.n());
    // Cauchy with lambda in micrometres: 1.5 + 0.01 / 0.25 at 500 nm.
    let c = Material::cauchy(1.5, 0.01, 0.0)
        .unwrap()
        .index_at(500.0)
        .unwrap();
    assert!((c.n() - 1.54).abs() < 1e-14);
    // Below a Sellmeier resonance there is no index: an error, not a NaN.
    let res = Material::sellmeier(&[(1.0, 0.25)]).unwrap();
    assert!(res.index_at(400.0).is_err());
    assert!(res.index_at(600.0).is_ok());
}

#[test]
fn invalid_input_is_rejected_with_a_message() {
    let e = Index::new(1.5, -0.1).unwrap_err().to_string();
    assert!(e.contains("gain"), "{e}");
    assert!(Index::new(f64::NAN, 0.0).is_err());
    assert!(Index::new(0.0, 0.0).is_err());
    let e = Layer::new(idx(2.0, 0.0).into(), -5.0)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "thickness -5 nm is negative");
    assert!(Layer::new(idx(2.0, 0.0).into(), f64::INFINITY).is_err());
    let e = Film::<f64>::new(
        500.0,
        idx(1.0, 0.0),
        &[(idx(2.0, 0.0), 10.0), (idx(2.0, 0.0), -5.0)],
        idx(1.5, 0.0),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(e, "layer 2: thickness -5 nm is negative");
    // An absorbing ambient, a wavelength of 0, an angle outside [0, 90].
    assert!(Film::<f64>::new(500.0, idx(1.0, 0.1), &[], idx(1.5, 0.0)).is_err());
    assert!(Film::<f64>::new(0.0, idx(1.0, 0.0), &[], idx(1.5, 0.0)).is_err());
    assert!(Incidence::degrees(90.5).is_err() && Incidence::degrees(-1.0).is_err());
    assert!(Incidence::degrees(f64::NAN).is_err());
    // Absurd magnitudes are errors, not NaNs downstream.
    assert!(Index::new(1e300, 0.0).is_err());
    assert!(Film::<f32>::new(
        1e-300,
        idx(1.0, 0.0),
        &[(idx(2.0, 0.0), 100.0)],
        idx(1.5, 0.0)
    )
    .is_err());
    assert!(Film::<f64>::new(
        500.0,
        idx(1.0, 0.0),
        &[(idx(2.0, 0.0), 1e300)],
        idx(1.5, 0.0)
    )
    .is_err());
}

#[test]
fn amplitudes_and_powers_agree_for_s_and_p() {
    // The amplitude path (one wave at a time) and the fused s+p power path must agree.
    let layers = [
        (idx(1.38, 0.0), 95.0),
        (idx(2.0, 0.3), 60.0),
        (idx(1.0, 0.0), 40.0),
    ];
    for n0 in [1.0, 1.5] {
        let f = film(480.0, n0, &layers, idx(3.1, 3.3));
        for a in ANGLES {
            for (wave, pol) in [(Wave::S, Polarization::S), (Wave::P, Polarization::P)] {
                let (r, _) = f.amplitudes(&deg(a), wave);
                let got = f.rt(&deg(a), pol).r;
                assert!((r.norm_sqr() - got).abs() < 1e-15, "{n0} {a} {pol}");
            }
        }
    }
}

/// Runs the built binary; returns (exit code, stdout, stderr).
fn specmap(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_specmap"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cli_prints_the_chrome_oxide_film_and_rejects_bad_layers() {
    let (code, out, _) = specmap(&[
        "thinfilm",
        "--layers",
        "2.7:270",
        "--substrate",
        "1.45",
        "--range",
        "380:780:5",
        "--json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in ["wavelengths_nm", "R", "T", "XYZ", "srgb8"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["R"].as_array().unwrap().len(), 81);
    // R at 380 nm is the Airy closed form.
    let r0 = v["R"][0].as_f64().unwrap();
    assert!((r0 - single_film_normal(1.0, 2.7, 1.45, 270.0, 380.0)).abs() < 1e-12);

    let (code, _, err) = specmap(&[
        "thinfilm",
        "--layers",
        "2.7:270,1.5:-5",
        "--substrate",
        "1.45",
    ]);
    assert_eq!(code, 1);
    assert_eq!(err.trim(), "error: layer 2: thickness -5 nm is negative");
    let (code, _, err) = specmap(&["thinfilm", "--layers", "2.7:270", "--substrate", "3.1-3.3i"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("substrate") && err.contains("gain medium"),
        "{err}"
    );
    let (code, _, err) = specmap(&["thinfilm", "--layers", "2.7", "--substrate", "1.45"]);
    assert_eq!(code, 1);
    assert!(
        err.contains("layer 1: '2.7' must be INDEX:THICKNESS_NM"),
        "{err}"
    );
}
