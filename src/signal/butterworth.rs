//! Digital Butterworth filters as second-order sections (SOS), designed the way scipy's
//! `butter(..., output='sos')` designs them so that coefficients agree with the reference
//! implementation to rounding: analog prototype poles, bilinear transform with frequency
//! prewarping, and scipy's `zpk2sos` "nearest" pole–zero pairing and section order.
//!
//! Second-order sections rather than one transfer function because a 4th-order high-pass at
//! 10 kHz / 4 MS/s has poles within 0.006 of z = 1: the expanded polynomial loses most of its
//! significant digits, the cascaded sections do not.

use super::SignalError;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// One second-order section `[b0, b1, b2, a0, a1, a2]`:
/// `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²) / (a0 + a1 z⁻¹ + a2 z⁻²)`, with `a0 = 1` as designed here.
pub type Sos = [f64; 6];

/// Pass band of a Butterworth design.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilterKind {
    HighPass,
    LowPass,
}

/// Highest order accepted: beyond 12 the design still works, but nothing in the pipeline needs
/// it and such filters are usually a configuration mistake.
const MAX_ORDER: usize = 12;

/// Digital Butterworth design as second-order sections, identical (to rounding) to scipy
/// `butter(order, cutoff_hz, btype, fs=fs, output='sos')`: bilinear transform with prewarping
/// (so the −3 dB point is exactly at `cutoff_hz`), `zpk2sos` with 'nearest' pairing, sections
/// ordered as scipy orders them (poles closest to the unit circle last) and the overall gain in
/// the first section. An odd order yields one first-order section, padded with a pole and a
/// zero at the origin (`b2 = a2 = 0`) exactly as scipy does.
///
/// Errors: `order` outside 1..=12, `fs` not finite and positive, `cutoff_hz` not strictly
/// between 0 and `fs/2`.
pub fn butterworth_sos(
    order: usize,
    cutoff_hz: f64,
    fs: f64,
    kind: FilterKind,
) -> Result<Vec<Sos>, SignalError> {
    if !(1..=MAX_ORDER).contains(&order) {
        return Err(SignalError::parameter(
            "order",
            order,
            format!("Butterworth order must be between 1 and {MAX_ORDER}"),
        ));
    }
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SignalError::parameter(
            "fs",
            fs,
            "sampling rate must be finite and positive",
        ));
    }
    // Normalised to Nyquist, as scipy does; checking the normalised value as well catches a
    // cutoff that rounds onto Nyquist.
    let wn = 2.0 * cutoff_hz / fs;
    if !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < fs / 2.0 && wn < 1.0) {
        return Err(SignalError::parameter(
            "cutoff_hz",
            cutoff_hz,
            format!("cutoff must lie strictly between 0 and fs/2 = {}", fs / 2.0),
        ));
    }

    // Analog prototype: poles on the left half of the unit circle, no zeros, unit gain. The
    // middle pole of an odd order is exactly −1 (exp of 0), so it stays exactly real.
    let n = order as f64;
    let prototype_poles: Vec<Complex64> = (0..order)
        .map(|i| {
            let m = (2 * i) as f64 - (n - 1.0); // −(N−1), −(N−3), …, N−1
            -Complex64::new(0.0, PI * m / (2.0 * n)).exp()
        })
        .collect();

    // Prewarp so that the digital cutoff lands exactly on `cutoff_hz` after the bilinear
    // transform (done, as in scipy, with a normalised sampling rate of 2).
    const NORMALISED_FS: f64 = 2.0;
    let warped = 2.0 * NORMALISED_FS * (PI * wn / NORMALISED_FS).tan();

    let (analog_zeros, analog_poles, analog_gain) = match kind {
        FilterKind::LowPass => {
            let poles: Vec<Complex64> = prototype_poles.iter().map(|p| p * warped).collect();
            (Vec::new(), poles, warped.powf(n))
        }
        FilterKind::HighPass => {
            // s → ω/s: poles invert about the circle of radius ω, the zeros at infinity move to
            // the origin, and the gain is corrected so the pass band stays at 1.
            let poles: Vec<Complex64> = prototype_poles
                .iter()
                .map(|p| Complex64::new(warped, 0.0) / p)
                .collect();
            let minus_pole_product = prototype_poles
                .iter()
                .fold(Complex64::new(1.0, 0.0), |acc, p| acc * -p);
            let gain = (Complex64::new(1.0, 0.0) / minus_pole_product).re;
            (vec![Complex64::new(0.0, 0.0); order], poles, gain)
        }
    };

    let (zeros, poles, gain) = bilinear(&analog_zeros, &analog_poles, analog_gain, NORMALISED_FS);
    zpk_to_sos(zeros, poles, gain)
}

/// Bilinear transform of an analog zero/pole/gain system: `z = (2fs + s)/(2fs − s)`. Zeros at
/// infinity (the excess of poles over zeros) land at Nyquist, z = −1.
fn bilinear(
    zeros: &[Complex64],
    poles: &[Complex64],
    gain: f64,
    fs: f64,
) -> (Vec<Complex64>, Vec<Complex64>, f64) {
    let fs2 = 2.0 * fs;
    let map = |s: &Complex64| (fs2 + s) / (fs2 - s);
    let mut digital_zeros: Vec<Complex64> = zeros.iter().map(map).collect();
    let digital_poles: Vec<Complex64> = poles.iter().map(map).collect();
    let excess_poles = poles.len().saturating_sub(zeros.len());
    digital_zeros.extend(std::iter::repeat_n(Complex64::new(-1.0, 0.0), excess_poles));
    let product = |roots: &[Complex64]| {
        roots
            .iter()
            .fold(Complex64::new(1.0, 0.0), |acc, r| acc * (fs2 - r))
    };
    let digital_gain = gain * (product(zeros) / product(poles)).re;
    (digital_zeros, digital_poles, digital_gain)
}

/// A root counts as real when its imaginary part is exactly zero (numpy's `isreal`); after
/// [`split_conjugate_pairs`] every root is either exactly real or has a positive imaginary part.
fn is_real(root: &Complex64) -> bool {
    root.im == 0.0
}

/// scipy's `_cplxreal`: keep one member (positive imaginary part, averaged with its partner) of
/// each conjugate pair, followed by the real roots. Both groups are sorted by real part.
/// Roots within 100 ulp of the real axis count as real.
fn split_conjugate_pairs(mut roots: Vec<Complex64>) -> Result<Vec<Complex64>, SignalError> {
    let tol = 100.0 * f64::EPSILON;
    roots.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then_with(|| a.im.abs().total_cmp(&b.im.abs()))
    });
    let nearly_real = |r: &Complex64| r.im.abs() <= tol * r.norm();
    let reals: Vec<Complex64> = roots
        .iter()
        .filter(|r| nearly_real(r))
        .map(|r| Complex64::new(r.re, 0.0))
        .collect();
    let mut upper: Vec<Complex64> = roots
        .iter()
        .filter(|r| !nearly_real(r) && r.im > 0.0)
        .copied()
        .collect();
    let mut lower: Vec<Complex64> = roots
        .iter()
        .filter(|r| !nearly_real(r) && r.im < 0.0)
        .copied()
        .collect();
    if upper.len() != lower.len() {
        return Err(unpaired_root());
    }
    // Runs of (nearly) equal real parts are ordered by the size of the imaginary part so that
    // partners line up.
    let mut start = 0;
    while start < upper.len() {
        let mut stop = start + 1;
        while stop < upper.len()
            && upper[stop].re - upper[stop - 1].re <= tol * upper[stop - 1].norm()
        {
            stop += 1;
        }
        upper[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        lower[start..stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        start = stop;
    }
    let mut out = Vec::with_capacity(upper.len() + reals.len());
    for (u, l) in upper.iter().zip(&lower) {
        if (u - l.conj()).norm() > tol * l.norm() {
            return Err(unpaired_root());
        }
        out.push((u + l.conj()) / 2.0);
    }
    out.extend(reals);
    Ok(out)
}

/// Only reachable if the design produced a complex root without its conjugate, which the
/// Butterworth construction cannot do; reported instead of panicking.
fn unpaired_root() -> SignalError {
    SignalError::parameter(
        "zpk",
        "design",
        "complex root without a matching conjugate (internal design error)",
    )
}

/// Index of the root in `roots` satisfying `accept` that is nearest to `target` (first one on
/// ties, like numpy's stable small-array argsort).
fn nearest_index(
    roots: &[Complex64],
    target: Complex64,
    accept: impl Fn(&Complex64) -> bool,
) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, r) in roots.iter().enumerate() {
        if !accept(r) {
            continue;
        }
        let d = (r - target).norm();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// Index of the pole closest to the unit circle (the "worst" one for a digital filter).
fn worst_pole_index(poles: &[Complex64]) -> Option<usize> {
    nearest_to_unit_circle(poles.iter().enumerate().map(|(i, p)| (i, *p)))
}

fn nearest_to_unit_circle(candidates: impl Iterator<Item = (usize, Complex64)>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, p) in candidates {
        let d = (1.0 - p.norm()).abs();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// Monic polynomial with the given roots, highest power first: `Π (x − rᵢ)`. Real for the root
/// sets used here (real roots or conjugate pairs), so only the real part is kept.
fn monic_poly(roots: &[Complex64]) -> Vec<f64> {
    let mut coeffs = vec![Complex64::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![Complex64::new(0.0, 0.0); coeffs.len() + 1];
        for (j, c) in coeffs.iter().enumerate() {
            next[j] += c;
            next[j + 1] += c * -r;
        }
        coeffs = next;
    }
    coeffs.iter().map(|c| c.re).collect()
}

/// One section from up to two zeros and two poles, right-aligned like scipy's `_single_zpksos`
/// (a missing root shortens the polynomial, leaving leading zeros).
fn section(zeros: &[Complex64], poles: &[Complex64]) -> Sos {
    let mut sos = [0.0; 6];
    let b = monic_poly(zeros);
    let a = monic_poly(poles);
    sos[3 - b.len()..3].copy_from_slice(&b);
    sos[6 - a.len()..6].copy_from_slice(&a);
    sos
}

/// scipy's `zpk2sos` with 'nearest' pairing for a digital filter: pad to equal, even numbers of
/// poles and zeros with roots at the origin, then repeatedly take the pole closest to the unit
/// circle, pair it with its conjugate (or the next worst real pole) and with the nearest zeros,
/// filling sections from the last to the first. Finally the gain goes into the first section.
fn zpk_to_sos(
    mut zeros: Vec<Complex64>,
    mut poles: Vec<Complex64>,
    gain: f64,
) -> Result<Vec<Sos>, SignalError> {
    let origin = Complex64::new(0.0, 0.0);
    if zeros.is_empty() && poles.is_empty() {
        return Ok(vec![[gain, 0.0, 0.0, 1.0, 0.0, 0.0]]);
    }
    let len = zeros.len().max(poles.len());
    zeros.resize(len, origin);
    poles.resize(len, origin);
    let n_sections = len.div_ceil(2);
    if len % 2 == 1 {
        zeros.push(origin);
        poles.push(origin);
    }
    let mut zeros = split_conjugate_pairs(zeros)?;
    let mut poles = split_conjugate_pairs(poles)?;

    let mut sections = vec![[0.0; 6]; n_sections];
    for si in (0..n_sections).rev() {
        let p1 = poles.remove(worst_pole_index(&poles).ok_or_else(unpaired_root)?);
        let real_poles_left = poles.iter().filter(|p| is_real(p)).count();
        let real_zeros_left = zeros.iter().filter(|z| is_real(z)).count();

        sections[si] = if is_real(&p1) && real_poles_left == 0 {
            // The last real pole: a first-order section padded with a pole at the origin.
            let z1 = take_nearest(&mut zeros, p1, is_real)?;
            section(&[z1, origin], &[p1, origin])
        } else if poles.len() + 1 == zeros.len()
            && !is_real(&p1)
            && real_poles_left == 1
            && real_zeros_left == 1
        {
            // One real pole and one real zero remain for a later section: this complex pole
            // must take a complex zero pair.
            let z1 = take_nearest(&mut zeros, p1, |z| !is_real(z))?;
            section(&[z1, z1.conj()], &[p1, p1.conj()])
        } else {
            let p2 = if is_real(&p1) {
                let candidates = poles
                    .iter()
                    .copied()
                    .enumerate()
                    .filter(|(_, p)| is_real(p));
                let idx = nearest_to_unit_circle(candidates).ok_or_else(unpaired_root)?;
                poles.remove(idx)
            } else {
                p1.conj()
            };
            if zeros.is_empty() {
                section(&[], &[p1, p2])
            } else {
                let z1 = take_nearest(&mut zeros, p1, |_| true)?;
                if !is_real(&z1) {
                    section(&[z1, z1.conj()], &[p1, p2])
                } else if zeros.is_empty() {
                    section(&[z1], &[p1, p2])
                } else {
                    let z2 = take_nearest(&mut zeros, p1, is_real)?;
                    section(&[z1, z2], &[p1, p2])
                }
            }
        };
    }
    if !(zeros.is_empty() && poles.is_empty()) {
        return Err(unpaired_root());
    }
    for b in &mut sections[0][..3] {
        *b *= gain;
    }
    Ok(sections)
}

/// Removes and returns the root nearest to `target` among those satisfying `accept`.
fn take_nearest(
    roots: &mut Vec<Complex64>,
    target: Complex64,
    accept: impl Fn(&Complex64) -> bool,
) -> Result<Complex64, SignalError> {
    let idx = nearest_index(roots, target, accept).ok_or_else(unpaired_root)?;
    Ok(roots.remove(idx))
}

/// Complex frequency response of the cascade at `f_hz` (scipy `sosfreqz` at one frequency):
/// `Π (b0 + b1 e^{−jω} + b2 e^{−2jω}) / (a0 + a1 e^{−jω} + a2 e^{−2jω})`, `ω = 2π f/fs`.
/// Non-finite or zero `fs` gives a non-finite result rather than an error: this is an
/// evaluation helper for reports and tests, not a validation point.
pub fn sos_response(sos: &[Sos], f_hz: f64, fs: f64) -> Complex64 {
    let z_inv = Complex64::new(0.0, -2.0 * PI * f_hz / fs).exp();
    let z_inv2 = z_inv * z_inv;
    sos.iter().fold(Complex64::new(1.0, 0.0), |acc, s| {
        let num = s[0] + z_inv * s[1] + z_inv2 * s[2];
        let den = s[3] + z_inv * s[4] + z_inv2 * s[5];
        acc * num / den
    })
}

/// Amplitude gain in dB of the zero-phase (forward–backward) application of the cascade at
/// `f_hz`: the two passes multiply to `|H|²`, so this is `20·log10(|H|²)`, twice the
/// single-pass dB. `−∞` at an exact zero of the response (e.g. DC for a high-pass).
pub fn zero_phase_gain_db(sos: &[Sos], f_hz: f64, fs: f64) -> f64 {
    20.0 * sos_response(sos, f_hz, fs).norm_sqr().log10()
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 4e6;

    /// Largest |a − b| / max|b| over all coefficients.
    fn max_rel_diff(got: &[Sos], want: &[Sos]) -> f64 {
        assert_eq!(got.len(), want.len(), "number of sections");
        let scale = want.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
        got.iter()
            .flatten()
            .zip(want.iter().flatten())
            .map(|(g, w)| (g - w).abs() / scale)
            .fold(0.0, f64::max)
    }

    /// Coefficient-wise relative difference (for the spec's 1e-14 "equal to scipy" claim).
    fn max_coeffwise_rel_diff(got: &[Sos], want: &[Sos]) -> f64 {
        assert_eq!(got.len(), want.len(), "number of sections");
        got.iter()
            .flatten()
            .zip(want.iter().flatten())
            .map(|(g, w)| {
                if *w == 0.0 {
                    g.abs()
                } else {
                    ((g - w) / w).abs()
                }
            })
            .fold(0.0, f64::max)
    }

    // docs/dmw.md and tests/data/signals/sosfiltfilt_testvector/sos.csv;
    // scipy 1.17.1: signal.butter(4, 10e3, 'highpass', fs=4e6, output='sos')
    const HP4_10K: [Sos; 2] = [
        [
            0.9796854871904037,
            -1.9593709743808074,
            0.9796854871904037,
            1.0,
            -1.971148608851042,
            0.9713918145668796,
        ],
        [1.0, -2.0, 1.0, 1.0, -1.9878047097960423, 0.9880499705872483],
    ];

    #[test]
    fn highpass_order4_matches_spec_and_scipy() {
        let sos = butterworth_sos(4, 10e3, FS, FilterKind::HighPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &HP4_10K);
        assert!(d <= 1e-14, "max relative coefficient difference {d:e}");
    }

    #[test]
    fn highpass_order4_matches_reference_sos_csv() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/signals/sosfiltfilt_testvector/sos.csv"
        );
        let text = std::fs::read_to_string(path).expect("reference sos.csv");
        let want: Vec<Sos> = text
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|s| s.trim().parse().unwrap()).collect();
                v.try_into().expect("6 coefficients per row")
            })
            .collect();
        let sos = butterworth_sos(4, 10e3, FS, FilterKind::HighPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &want);
        assert!(d <= 1e-14, "max relative coefficient difference {d:e}");
    }

    #[test]
    fn highpass_order2_matches_scipy() {
        // scipy 1.17.1: signal.butter(2, 10e3, 'highpass', fs=4e6, output='sos')
        let want = [[
            0.9889542480671399,
            -1.9779084961342799,
            0.9889542480671399,
            1.0,
            -1.9777864837767636,
            0.9780305084917958,
        ]];
        let sos = butterworth_sos(2, 10e3, FS, FilterKind::HighPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &want);
        assert!(d <= 1e-14, "{d:e}");
    }

    #[test]
    fn highpass_odd_order3_has_padded_first_order_section_like_scipy() {
        // scipy 1.17.1: signal.butter(3, 10e3, 'highpass', fs=4e6, output='sos')
        let want = [
            [
                0.9844146043678856,
                -0.9844146043678856,
                0.0,
                1.0,
                -0.9844141274160969,
                0.0,
            ],
            [1.0, -2.0, 1.0, 1.0, -1.9841702689557368, 0.9844150813196745],
        ];
        let sos = butterworth_sos(3, 10e3, FS, FilterKind::HighPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &want);
        assert!(d <= 1e-14, "{d:e}");
        assert_eq!((sos[0][2], sos[0][5]), (0.0, 0.0));
    }

    #[test]
    fn lowpass_order4_and_order5_match_scipy() {
        // scipy 1.17.1: signal.butter(4, 500e3, 'lowpass', fs=4e6, output='sos')
        let want4 = [
            [
                0.010209480791203138,
                0.020418961582406275,
                0.010209480791203138,
                1.0,
                -0.8553979327751704,
                0.20971535775655478,
            ],
            [1.0, 2.0, 1.0, 1.0, -1.1130298541633479, 0.5740619150839545],
        ];
        let sos = butterworth_sos(4, 500e3, FS, FilterKind::LowPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &want4);
        assert!(d <= 1e-14, "order 4: {d:e}");

        // scipy 1.17.1: signal.butter(5, 500e3, 'lowpass', fs=4e6, output='sos')
        // (exercises the pairing rule that gives a complex pole pair a zero at the origin)
        let want5 = [
            [
                0.003279216306360205,
                0.00655843261272041,
                0.003279216306360205,
                1.0,
                -0.4142135623730951,
                0.0,
            ],
            [1.0, 2.0, 1.0, 1.0, -0.8995918097335953, 0.2722149379250073],
            [1.0, 1.0, 0.0, 1.0, -1.1606108028714728, 0.6413515380575632],
        ];
        let sos = butterworth_sos(5, 500e3, FS, FilterKind::LowPass).unwrap();
        let d = max_rel_diff(&sos, &want5);
        assert!(d <= 1e-14, "order 5: {d:e}");
    }

    #[test]
    fn highpass_order12_matches_scipy() {
        // scipy 1.17.1: signal.butter(12, 1e3, 'highpass', fs=48e3, output='sos')
        let want = [
            [
                0.6053774634684393,
                -1.2107549269368787,
                0.6053774634684393,
                1.0,
                -1.7556870941449176,
                0.7708368488713769,
            ],
            [1.0, -2.0, 1.0, 1.0, -1.7695043485128368, 0.7847733317825629],
            [1.0, -2.0, 1.0, 1.0, -1.7968226455102578, 0.8123273572878915],
            [1.0, -2.0, 1.0, 1.0, -1.8369286382471892, 0.8527794230551778],
            [1.0, -2.0, 1.0, 1.0, -1.8885559538890464, 0.9048522287685677],
            [1.0, -2.0, 1.0, 1.0, -1.9496729749339174, 0.9664966261788114],
        ];
        let sos = butterworth_sos(12, 1e3, 48e3, FilterKind::HighPass).unwrap();
        let d = max_coeffwise_rel_diff(&sos, &want);
        assert!(d <= 1e-13, "{d:e}");
    }

    /// `value` rounds to `printed` at the printed number of decimals.
    fn assert_printed(value: f64, printed: f64, decimals: i32, what: &str) {
        let half_unit = 0.5 * 10f64.powi(-decimals);
        assert!(
            (value - printed).abs() <= half_unit,
            "{what}: {value} does not round to {printed}"
        );
    }

    #[test]
    fn response_table_of_spec_3_6() {
        let hp4 = butterworth_sos(4, 10e3, FS, FilterKind::HighPass).unwrap();
        // (f, single-pass dB, zero-phase dB, decimals printed in the spec)
        let rows = [
            (1e3, -80.00, -160.00, 2),
            (2e3, -55.92, -111.84, 2),
            (5e3, -24.10, -48.20, 2),
            (10e3, -3.010, -6.021, 3),
            (20e3, -0.0169, -0.0338, 4),
        ];
        for (f, single, zero_phase, decimals) in rows {
            let single_db = 20.0 * sos_response(&hp4, f, FS).norm().log10();
            assert_printed(single_db, single, decimals, &format!("single pass {f} Hz"));
            let zp_db = zero_phase_gain_db(&hp4, f, FS);
            assert_printed(zp_db, zero_phase, decimals, &format!("zero phase {f} Hz"));
            assert!((zp_db - 2.0 * single_db).abs() < 1e-9);
        }
        // 50 kHz: −1.1e-5 / −2.2e-5 dB (two significant digits)
        let single_db = 20.0 * sos_response(&hp4, 50e3, FS).norm().log10();
        assert!((single_db + 1.1e-5).abs() <= 0.05e-5, "{single_db:e}");
        assert!((zero_phase_gain_db(&hp4, 50e3, FS) + 2.2e-5).abs() <= 0.05e-5);

        let hp2 = butterworth_sos(2, 10e3, FS, FilterKind::HighPass).unwrap();
        for (f, single, zero_phase) in [(1e3, -40.00, -80.00), (5e3, -12.30, -24.61)] {
            let single_db = 20.0 * sos_response(&hp2, f, FS).norm().log10();
            assert_printed(single_db, single, 2, &format!("order 2 single {f} Hz"));
            assert_printed(zero_phase_gain_db(&hp2, f, FS), zero_phase, 2, "order 2 zp");
        }
    }

    #[test]
    fn cutoff_is_minus_3db_for_low_and_high_pass_of_any_order() {
        for order in 1..=12 {
            for kind in [FilterKind::HighPass, FilterKind::LowPass] {
                let sos = butterworth_sos(order, 123e3, FS, kind).unwrap();
                let g = zero_phase_gain_db(&sos, 123e3, FS);
                assert!(
                    (g - 20.0 * 0.5f64.log10()).abs() < 1e-9,
                    "{order} {kind:?}: {g}"
                );
                assert_eq!(sos.len(), order.div_ceil(2));
                assert!(sos.iter().all(|s| s[3] == 1.0));
            }
        }
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let bad = [
            (0, 10e3, FS),
            (13, 10e3, FS),
            (4, 0.0, FS),
            (4, -1.0, FS),
            (4, 2e6, FS),
            (4, 3e6, FS),
            (4, f64::NAN, FS),
            (4, 10e3, 0.0),
            (4, 10e3, -FS),
            (4, 10e3, f64::INFINITY),
            (4, 10e3, f64::NAN),
        ];
        for (order, fc, fs) in bad {
            for kind in [FilterKind::HighPass, FilterKind::LowPass] {
                let r = butterworth_sos(order, fc, fs, kind);
                assert!(
                    matches!(r, Err(SignalError::Parameter { .. })),
                    "{order} {fc} {fs}: {r:?}"
                );
            }
        }
    }
}
