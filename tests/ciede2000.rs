//! CIEDE2000 against the 34 published pairs of Sharma, Wu and Dalal (2005): tests/data/.

use specmap::colorimetry::{delta_e_2000, Lab};

#[test]
fn sharma_wu_dalal_2005_pairs() {
    let text = include_str!("data/ciede2000_sharma2005.csv");
    let mut n = 0;
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        let v: Vec<f64> = line.split(',').map(|f| f.trim().parse().unwrap()).collect();
        let (lab1, lab2) = (Lab([v[1], v[2], v[3]]), Lab([v[4], v[5], v[6]]));
        let expected = v[7];
        for (a, b) in [(lab1, lab2), (lab2, lab1)] {
            let de = delta_e_2000(a, b);
            // Published to 4 decimals.
            assert!(
                (de - expected).abs() < 5e-5,
                "pair {}: {de} vs {expected}",
                v[0]
            );
        }
        n += 1;
    }
    assert_eq!(n, 34);
}
