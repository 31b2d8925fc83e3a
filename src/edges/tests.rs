use super::*;
use crate::histogram::{Clear, Histogram};
use crate::pixel::PixelFormat;
use crate::region::for_each_in_ellipse;

#[test]
fn a_target_with_weak_gradients_gets_the_strength_its_share_reaches() {
    // Reason: by hand. Grey level 3·x: every pixel's Sobel gx is
    // 4 · (3(x+1) − 3(x−1)) = 24 and gy is 0, so every sample has
    // strength 24. The 64 bins below a threshold of 100 are 2 wide, so
    // 24 is a bin edge and comes back exactly.
    let (w, h) = (64, 48);
    let ramp: Vec<u8> = (0..w * h).map(|i| (3 * (i % w)) as u8).collect();
    let f = Frame::packed(&ramp, w, h, PixelFormat::Gray8).unwrap();
    let e = Ellipse { cx: 32.0, cy: 24.0, hx: 20.0, hy: 15.0 };
    assert_eq!(soft_threshold(&f, &e, 100, 10), 24, "none reach 100: lowered to what all reach");
    assert_eq!(soft_threshold(&f, &e, 20, 10), 20, "all reach 20: kept");
    assert_eq!(soft_threshold(&f, &e, 100, 0), 100, "0% keeps the threshold fixed");
    // A flat patch has no strength at all: the floor.
    let flat = vec![50u8; w * h];
    let f = Frame::packed(&flat, w, h, PixelFormat::Gray8).unwrap();
    assert_eq!(soft_threshold(&f, &e, 100, 10), MIN_EDGE_THRESHOLD);
    // An ellipse off the frame has no samples: unchanged.
    let off = Ellipse { cx: -100.0, cy: -100.0, hx: 5.0, hy: 5.0 };
    assert_eq!(soft_threshold(&f, &off, 100, 10), 100);
}

#[test]
fn the_share_decides_whether_a_sharp_edge_keeps_the_threshold() {
    // Reason: by hand. A vertical step from 0 to 100 at x = 32 gives
    // strength 4 · 100 = 400 in columns 31 and 32 and 0 elsewhere. In a
    // 41-px-wide ellipse on a 1-px lattice (area 41·21 < 1024 samples)
    // those 2 columns are between 2/41 ≈ 5% of a full row and all of a
    // row 1 or 2 px wide, and over the whole ellipse between 5% and 10%
    // (counted below), so 3% keeps 100, and 20% drops to the floor: the
    // rest of the samples have strength 0.
    let (w, h) = (64, 32);
    let step: Vec<u8> = (0..w * h).map(|i| if i % w >= 32 { 100 } else { 0 }).collect();
    let f = Frame::packed(&step, w, h, PixelFormat::Gray8).unwrap();
    let e = Ellipse { cx: 32.0, cy: 16.0, hx: 20.5, hy: 10.5 };
    let (mut n, mut strong) = (0, 0);
    for_each_in_ellipse(&f, &e, Lattice::with_step(Sampling::Full, 1), |_, x, y, _| {
        if y > 0 && y + 1 < h {
            n += 1;
            strong += (x == 31 || x == 32) as u32;
        }
    });
    assert!(20 * strong > n && 10 * strong < n, "{strong} of {n}: the share is between 5% and 10%");
    assert_eq!(soft_threshold(&f, &e, 100, 3), 100);
    assert_eq!(soft_threshold(&f, &e, 100, 20), MIN_EDGE_THRESHOLD);
}

#[test]
fn sobel_on_a_hand_computed_patch() {
    // Reason: by hand, for the patch
    //   10 20 30
    //   10 20 30
    //   10 20 60
    // gx = (30 + 2·30 + 60) − (10 + 2·10 + 10) = 150 − 40 = 110
    // gy = (10 + 2·20 + 60) − (10 + 2·20 + 30) = 110 − 80 = 30
    assert_eq!(sobel([10, 20, 30, 10, 20, 30, 10, 20, 60]), (110, 30));
    // A flat patch has no gradient.
    assert_eq!(sobel([7; 9]), (0, 0));
}

#[test]
fn orientation_bins_of_known_angles() {
    // Reason: with 8 bins of 22.5°, an edge at angle θ belongs to bin
    // floor((θ mod 180) / 22.5); test the middle of every bin, and the
    // opposite direction (θ + 180°), which is the same orientation.
    for bins in [2usize, 4, 8, 16] {
        let width = 180.0 / bins as f64;
        for k in 0..bins {
            let theta = (k as f64 + 0.5) * width;
            let (gx, gy) = ((1000.0 * theta.to_radians().cos()) as i32, (1000.0 * theta.to_radians().sin()) as i32);
            assert_eq!(orientation_bin(gx, gy, bins), k, "{bins} bins, {theta}°");
            assert_eq!(orientation_bin(-gx, -gy, bins), k, "{bins} bins, {theta}° + 180°");
        }
    }
    // Horizontal gradients (vertical edges) are bin 0 either way.
    assert_eq!(orientation_bin(50, 0, 8), 0);
    assert_eq!(orientation_bin(-50, 0, 8), 0);
    // Vertical gradients are the first bin past 90°.
    assert_eq!(orientation_bin(0, 50, 8), 4);
}

#[test]
fn orientation_bins_match_the_angle_of_random_gradients() {
    // Reason: the bin is floor((atan2(gy, gx) mod 180°) / (180° / bins))
    // by definition; checked against f64 atan2 on random Sobel-sized
    // gradients, skipping those within 0.05° of a boundary (the
    // direction table is rounded to 1/4096). Other counts act as the
    // power of two below them, as documented.
    let mut next = crate::testing::lcg(11);
    let mut checked = 0;
    for _ in 0..20_000 {
        let (gx, gy) = ((next() >> 21) as i32 - 1024, (next() >> 21) as i32 - 1024);
        if gx == 0 && gy == 0 {
            continue;
        }
        let angle = (gy as f64).atan2(gx as f64).to_degrees().rem_euclid(180.0);
        for bins in [2usize, 4, 8, 16] {
            let width = 180.0 / bins as f64;
            let off = angle % width;
            if off < 0.05 || width - off < 0.05 {
                continue;
            }
            assert_eq!(orientation_bin(gx, gy, bins), (angle / width) as usize, "({gx}, {gy}), {bins} bins");
            checked += 1;
        }
        assert_eq!(orientation_bin(gx, gy, 3), orientation_bin(gx, gy, 2));
        assert_eq!(orientation_bin(gx, gy, 12), orientation_bin(gx, gy, 8));
        assert_eq!(orientation_bin(gx, gy, 0), 0);
        assert_eq!(orientation_bin(gx, gy, 1), 0);
    }
    assert!(checked > 70_000, "{checked}");
}

fn stripes(w: usize, h: usize, vertical: bool) -> Vec<u8> {
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let u = if vertical { x } else { y };
            if (u / 4) % 2 == 0 { 30 } else { 220 }
        })
        .collect()
}

#[test]
fn synthetic_edges_land_in_their_orientation_bins() {
    // Reason: vertical stripes have horizontal gradients (bin 0);
    // horizontal stripes have vertical gradients (bin 4 of 8).
    for (vertical, want) in [(true, 0usize), (false, 4)] {
        let px = stripes(40, 40, vertical);
        let f = Frame::packed(&px, 40, 40, PixelFormat::Gray8).unwrap();
        let mut map = EdgeMap::<2048>::new();
        map.compute(
            &f,
            (0, 0, 40, 40),
            EdgeParams { bins: 8, threshold: 50, sampling: Sampling::Full, step: 1, flat_bin: false },
        );
        assert_eq!(map.spacing(), 1);
        let mut h = Histogram::<16>::new();
        let l = Lattice::new(Sampling::Full, 0, 10.0, 10.0);
        for_each_in_ellipse(&f, &Ellipse { cx: 20.0, cy: 20.0, hx: 10.0, hy: 10.0 }, l, |_, x, y, w| {
            if let Some(bin) = map.bin_at(x, y) {
                h.add(bin, w);
            }
        });
        assert!(h.total() > 0);
        assert_eq!(h.counts()[want], h.total(), "vertical={vertical}: {:?}", &h.counts()[..8]);
    }
}

/// [`sobel`] of the 3x3 window of grey levels `l` around `(x, y)`, an
/// inner pixel: the per-pixel definition the maps are checked against.
fn sobel_at(l: &impl Fn(usize, usize) -> i32, x: usize, y: usize) -> (i32, i32) {
    let (xs, ys) = ([x - 1, x, x + 1], [y - 1, y, y + 1]);
    sobel(core::array::from_fn(|i| l(xs[i % 3], ys[i / 3])))
}

#[test]
fn wide_maps_match_direct_sobel_across_column_tiles() {
    // Reason: cross-check of the row-ring fill against the per-pixel
    // definition on a frame wide enough for several column tiles, on
    // both lattices of step 1, in RGB565 (the two-table luma).
    let (w, h) = (431usize, 23usize);
    let px = crate::testing::noise_bytes(5, w * h * 2);
    let f = Frame::packed(&px, w, h, PixelFormat::Rgb565).unwrap();
    let l = |x: usize, y: usize| crate::frame::luma(f.rgb(x, y).unwrap()) as i32;
    for sampling in [Sampling::Checkerboard, Sampling::Full] {
        let mut map = EdgeMap::<8192>::new();
        let (x0, y0) = (2usize, 1usize);
        map.compute(&f, (x0, y0, w, h), EdgeParams { bins: 8, threshold: 90, sampling, step: 1, flat_bin: true });
        assert_eq!(map.spacing(), 1);
        let lattice = Lattice::with_step(sampling, 1);
        for y in y0..h {
            for x in x0..w {
                if !lattice.contains(x, y) {
                    continue;
                }
                let want = if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
                    None
                } else {
                    let (gx, gy) = sobel_at(&l, x, y);
                    Some(if gx * gx + gy * gy < 90 * 90 { 8 } else { orientation_bin(gx, gy, 8) })
                };
                assert_eq!(map.bin_at(x, y), want, "{sampling:?} at ({x}, {y})");
            }
        }
    }
}

#[test]
fn every_pixel_format_reads_the_map_its_lumas_give() {
    // Reason: cross-check of the per-format luma readers (whole spans
    // for dense cells, three columns a cell for sparse ones) against
    // the frame's own per-pixel luma, the definition, in each camera
    // format, on lattices dense (step 1) and sparse (steps 2 and 3,
    // checkerboard and full).
    let (w, h) = (38usize, 29usize);
    for format in [PixelFormat::Rgb565, PixelFormat::Yuv422, PixelFormat::Gray8, PixelFormat::Rgb888] {
        let px = crate::testing::noise_bytes(7, w * h * format.bytes_per_pixel());
        let f = Frame::packed(&px, w, h, format).unwrap();
        let l = |x: usize, y: usize| f.luma(x, y).unwrap() as i32;
        for (sampling, step) in [
            (Sampling::Full, 1),
            (Sampling::Checkerboard, 1),
            (Sampling::Full, 2),
            (Sampling::Full, 3),
            (Sampling::Checkerboard, 3),
        ] {
            let params = EdgeParams { bins: 8, threshold: 60, sampling, step, flat_bin: false };
            let mut map = EdgeMap::<4096>::new();
            map.compute(&f, (1, 1, w, h), params);
            assert_eq!(map.spacing(), 1);
            let lattice = Lattice::with_step(sampling, step);
            let mut n = 0;
            for y in 1..h - 1 {
                for x in 1..w - 1 {
                    if lattice.contains(x, y) {
                        let (gx, gy) = sobel_at(&l, x, y);
                        let want = (gx * gx + gy * gy >= 60 * 60).then(|| orientation_bin(gx, gy, 8));
                        assert_eq!(map.bin_at(x, y), want, "{format:?} {sampling:?} step {step} at ({x}, {y})");
                        n += 1;
                    }
                }
            }
            assert!(n > 10, "{format:?} {sampling:?} step {step}: {n} cells checked");
        }
    }
}

#[test]
fn map_matches_direct_sobel_on_every_lattice() {
    // Reason: cross-check the map (sliding window, shared columns,
    // lattice-indexed cells) against the plain per-pixel definition on a
    // random image, at every sampled pixel of several lattices, and
    // against the region walk's own order of cells.
    let (w, h) = (37usize, 29usize);
    let px = crate::testing::noise_bytes(99, w * h * 3);
    let f = Frame::packed(&px, w, h, PixelFormat::Rgb888).unwrap();
    let l = |x: usize, y: usize| crate::frame::luma(f.rgb(x, y).unwrap()) as i32;
    let direct = |x: usize, y: usize, bins: usize| {
        if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
            return None;
        }
        let (gx, gy) = sobel_at(&l, x, y);
        (gx * gx + gy * gy >= 120 * 120).then(|| orientation_bin(gx, gy, bins))
    };
    // 8 bins take 4-bit cells, 16 a byte each.
    for (sampling, step, bins) in [Sampling::Full, Sampling::Checkerboard, Sampling::Quarter]
        .into_iter()
        .flat_map(|s| [1usize, 2, 3].map(|step| (s, step)))
        .flat_map(|(s, step)| [8usize, 16].map(|b| (s, step, b)))
    {
        {
            let mut map = EdgeMap::<4096>::new();
            let (x0, y0) = (3usize, 2usize);
            let params = EdgeParams { bins, threshold: 120, sampling, step, flat_bin: false };
            map.compute(&f, (x0, y0, w, h), params);
            assert_eq!(map.spacing(), 1);
            let lattice = Lattice::with_step(sampling, step);
            let mut n = 0;
            for y in y0..h {
                for x in x0..w {
                    if lattice.contains(x, y) {
                        assert_eq!(map.bin_at(x, y), direct(x, y, bins), "{sampling:?} step {step} at ({x}, {y})");
                        n += 1;
                    }
                }
            }
            assert!(n > 20, "{n} lattice pixels");
            // A region walk reads the same cells along each row.
            let e = Ellipse { cx: 20.0, cy: 15.0, hx: 12.0, hy: 9.0 };
            let mut via_walk = Histogram::<17>::new();
            let whole = crate::histogram::Layout::whole(crate::colour::Binning::Rgb8x8x8);
            Histogram::<512>::new().compute_with(&f, &e, &whole, lattice, Some((&map, &mut via_walk)), Clear::All);
            let mut via_lookup = Histogram::<17>::new();
            for_each_in_ellipse(&f, &e, lattice, |_, x, y, w| {
                if let Some(b) = direct(x, y, bins) {
                    via_lookup.add(b, w);
                }
            });
            assert!(via_lookup.total() > 0);
            assert_eq!(via_walk, via_lookup, "{sampling:?} step {step}");
            // A map too small for the region is coarsened; the walk then
            // reads the cell `bin_at` names for each sample.
            let mut small = EdgeMap::<16>::new();
            small.compute(&f, (x0, y0, w, h), params);
            assert!(small.spacing() > 1);
            let mut via_walk = Histogram::<17>::new();
            Histogram::<512>::new().compute_with(&f, &e, &whole, lattice, Some((&small, &mut via_walk)), Clear::All);
            let mut via_lookup = Histogram::<17>::new();
            for_each_in_ellipse(&f, &e, lattice, |_, x, y, w| {
                if let Some(b) = small.bin_at(x, y) {
                    via_lookup.add(b, w);
                }
            });
            assert!(via_lookup.total() > 0);
            assert_eq!(via_walk, via_lookup, "coarse: {sampling:?} step {step}");
        }
    }
}

#[test]
fn weak_gradients_are_dropped_and_the_map_coarsens_to_fit() {
    let flat = vec![100u8; 64 * 64];
    let f = Frame::packed(&flat, 64, 64, PixelFormat::Gray8).unwrap();
    let mut map = EdgeMap::<256>::new();
    // 64x64 = 4096 pixels into 256 cells: spacing 4.
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 8, threshold: 1, sampling: Sampling::Full, step: 1, flat_bin: false },
    );
    assert_eq!(map.spacing(), 4);
    assert_eq!(map.bin_at(30, 30), None, "a flat frame has no edges");
    assert_eq!(map.bin_at(100, 30), None, "outside the frame");
    // Stripes 2 grey levels apart: a gradient of 8, under a threshold of 10.
    let faint: Vec<u8> = (0..64 * 64).map(|i| if (i % 64) / 4 % 2 == 0 { 100 } else { 102 }).collect();
    let f = Frame::packed(&faint, 64, 64, PixelFormat::Gray8).unwrap();
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 8, threshold: 10, sampling: Sampling::Full, step: 1, flat_bin: false },
    );
    assert!((0..64).all(|x| map.bin_at(x, 30).is_none()));
    // Every 3rd row and column: 22x22 lattice points, 242 bytes of 4-bit
    // cells: they fit. With 16 bins, a byte per cell: every 2nd of them.
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 8, threshold: 5, sampling: Sampling::Full, step: 3, flat_bin: false },
    );
    assert_eq!(map.spacing(), 1);
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 16, threshold: 5, sampling: Sampling::Full, step: 3, flat_bin: false },
    );
    assert_eq!(map.spacing(), 2, "the budget of 256 bytes still rules");
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 8, threshold: 5, sampling: Sampling::Full, step: 1, flat_bin: false },
    );
    assert!((0..64).any(|x| map.bin_at(x, 30).is_some()));
    // With a flat bin, the weak pixels are counted there (bin 8 of 8 + 1).
    // The map's cells are 4 px apart; those of x < 4 sit on the border.
    map.compute(
        &f,
        (0, 0, 64, 64),
        EdgeParams { bins: 8, threshold: 10, sampling: Sampling::Full, step: 1, flat_bin: true },
    );
    assert!((4..64).all(|x| map.bin_at(x, 30) == Some(8)));
    assert_eq!(map.bin_at(0, 30), None, "the border has no Sobel window");
}
