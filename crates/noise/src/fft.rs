//! In-place radix-2 FFT: the filter's autocorrelation (`filter::FilteredAllan`) and diagnose's
//! Welch spectrum.

/// In-place radix-2 FFT (iterative Cooley-Tukey); `re.len()` a power of two.
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    bit_reverse(re, im);
    let twiddles = stage_twiddles(n);
    let mut len = 2;
    while len <= n {
        let half = len / 2;
        // This stage's twiddles, contiguous: the butterflies of a block vectorise.
        let (cos, sin) = (
            &twiddles.cos[half - 1..len - 1],
            &twiddles.sin[half - 1..len - 1],
        );
        for (re, im) in re.chunks_exact_mut(len).zip(im.chunks_exact_mut(len)) {
            let ((re_a, re_b), (im_a, im_b)) = (re.split_at_mut(half), im.split_at_mut(half));
            for k in 0..half {
                let (s, c) = (sin[k], cos[k]);
                let (tr, ti) = (re_b[k] * c - im_b[k] * s, re_b[k] * s + im_b[k] * c);
                re_b[k] = re_a[k] - tr;
                im_b[k] = im_a[k] - ti;
                re_a[k] += tr;
                im_a[k] += ti;
            }
        }
        len <<= 1;
    }
}

/// The input in bit-reversed order (the iterative transform's first step).
fn bit_reverse(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
}

/// The twiddles of every stage of an `n`-point transform: stage `len` (block length) at
/// `len / 2 - 1 .. len - 1`, its k-th e^{-2 pi i k (n / len) / n}, k < len / 2.
struct Twiddles {
    cos: Vec<f64>,
    sin: Vec<f64>,
}

/// [`Twiddles`] of size `n`, made once per thread and size: the diagnosis transforms the same
/// few sizes hundreds of times, and the sines were a quarter of the time. Each is the same
/// `sin_cos` of the same argument as when made afresh.
fn stage_twiddles(n: usize) -> std::rc::Rc<Twiddles> {
    use std::cell::RefCell;
    use std::collections::HashMap;
    use std::rc::Rc;
    thread_local! {
        static CACHE: RefCell<HashMap<usize, Rc<Twiddles>>> = RefCell::new(HashMap::new());
    }
    CACHE.with(|cache| {
        Rc::clone(cache.borrow_mut().entry(n).or_insert_with(|| {
            // e^{-2 pi i k / n}, k < n/2; a stage of length len uses every (n/len)-th.
            let base: Vec<(f64, f64)> = (0..n / 2)
                .map(|k| (-std::f64::consts::TAU * k as f64 / n as f64).sin_cos())
                .collect();
            let stages = (1..=n.max(1).ilog2()).map(|b| (1usize << b, n >> b));
            let picked: Vec<(f64, f64)> = stages
                .flat_map(|(len, stride)| (0..len / 2).map(move |k| k * stride))
                .map(|i| base[i])
                .collect();
            Rc::new(Twiddles {
                sin: picked.iter().map(|t| t.0).collect(),
                cos: picked.iter().map(|t| t.1).collect(),
            })
        }))
    })
}

/// Autocorrelation a(d) = sum_i x_i x_{i+d}, d = 0..len-1, through the FFT of the zero-padded
/// sequence (|X|^2 transformed back): O(L log L) instead of O(L^2). Rounding is about 1e-16 of
/// a(0) times log2 of the padded length, absolute.
pub fn autocorrelation(x: &[f64]) -> Vec<f64> {
    let l = x.len();
    let n = (2 * l).next_power_of_two();
    let mut re = vec![0.0; n];
    let mut im = vec![0.0; n];
    re[..l].copy_from_slice(x);
    fft(&mut re, &mut im);
    for (r, i) in re.iter_mut().zip(im.iter_mut()) {
        *r = *r * *r + *i * *i;
        *i = 0.0;
    }
    // Inverse by the forward transform of the conjugate (|X|^2 is real and even: its own conjugate).
    fft(&mut re, &mut im);
    re.truncate(l);
    re.iter_mut().for_each(|v| *v /= n as f64);
    re
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn normals(n: usize, seed: u64) -> Vec<f64> {
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
    }

    /// The transform with cached, per-stage twiddles gives the bits of the one that made its
    /// twiddles each call and read them at a stride (as first written, the bit reversal aside,
    /// which is unchanged), at every size, twice (the second from the cache).
    #[test]
    fn cached_stage_twiddles_give_the_same_bits() {
        let strided = |re: &mut [f64], im: &mut [f64]| {
            let n = re.len();
            bit_reverse(re, im);
            let twiddle: Vec<(f64, f64)> = (0..n / 2)
                .map(|k| (-std::f64::consts::TAU * k as f64 / n as f64).sin_cos())
                .collect();
            let mut len = 2;
            while len <= n {
                let stride = n / len;
                for start in (0..n).step_by(len) {
                    for k in 0..len / 2 {
                        let (s, c) = twiddle[k * stride];
                        let (a, b) = (start + k, start + k + len / 2);
                        let (tr, ti) = (re[b] * c - im[b] * s, re[b] * s + im[b] * c);
                        re[b] = re[a] - tr;
                        im[b] = im[a] - ti;
                        re[a] += tr;
                        im[a] += ti;
                    }
                }
                len <<= 1;
            }
        };
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for b in 0..13 {
            let n = 1usize << b;
            for round in 0..2 {
                let (x, y) = (normals(n, 100 + b), normals(n, 200 + b + round));
                let (mut re, mut im) = (x.clone(), y.clone());
                let (mut re0, mut im0) = (x, y);
                fft(&mut re, &mut im);
                strided(&mut re0, &mut im0);
                assert_eq!(bits(&re), bits(&re0), "n {n}");
                assert_eq!(bits(&im), bits(&im0), "n {n}");
            }
        }
    }

    #[test]
    fn fft_matches_direct_dft() {
        let x = normals(64, 1);
        let (mut re, mut im) = (x.clone(), vec![0.0; 64]);
        fft(&mut re, &mut im);
        for k in [0usize, 1, 7, 31, 32] {
            let (mut a, mut b) = (0.0, 0.0);
            for (n, v) in x.iter().enumerate() {
                let w = -std::f64::consts::TAU * (k * n) as f64 / 64.0;
                a += v * w.cos();
                b += v * w.sin();
            }
            assert!(
                (a - re[k]).abs() < 1e-9 && (b - im[k]).abs() < 1e-9,
                "bin {k}"
            );
        }
    }

    #[test]
    fn autocorrelation_matches_the_direct_sum() {
        for l in [1usize, 2, 7, 64, 300] {
            let x = normals(l, l as u64);
            let a = autocorrelation(&x);
            for d in 0..l {
                let direct: f64 = (0..l - d).map(|i| x[i] * x[i + d]).sum();
                assert!((a[d] - direct).abs() < 1e-12 * a[0].max(1.0), "l {l} d {d}");
            }
        }
    }
}
