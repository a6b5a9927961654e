//! The map picture (like the paper's Fig. 7/8): the occupancy map, each source's cluster
//! particles, the estimates with 2-sigma ellipses, the robot's trajectory, and the ground
//! truth when known. Written as PNG with the `png` crate; the drawing is our own.

use std::path::Path;

use anyhow::{Context, Result};
use asm::map::{Cell, OccupancyMap};
use asm::{MapResult, Pose};

/// Pixels per map cell.
const SCALE: usize = 3;

const PALETTE: [[u8; 3]; 8] = [
    [230, 159, 0],
    [86, 180, 233],
    [0, 158, 115],
    [240, 228, 66],
    [0, 114, 178],
    [213, 94, 0],
    [204, 121, 167],
    [120, 120, 120],
];

struct Canvas<'a> {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
    map: &'a OccupancyMap,
}

impl Canvas<'_> {
    fn to_px(&self, p: [f64; 2]) -> (f64, f64) {
        let r = self.map.resolution() / SCALE as f64;
        let o = self.map.origin();
        ((p[0] - o[0]) / r, self.h as f64 - (p[1] - o[1]) / r)
    }

    fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = 3 * (y as usize * self.w + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    fn disk(&mut self, p: [f64; 2], radius_px: f64, c: [u8; 3]) {
        let (cx, cy) = self.to_px(p);
        let r = radius_px.ceil() as i64;
        for dy in -r..=r {
            for dx in -r..=r {
                if (dx * dx + dy * dy) as f64 <= radius_px * radius_px {
                    self.put(cx as i64 + dx, cy as i64 + dy, c);
                }
            }
        }
    }

    fn line(&mut self, a: (f64, f64), b: (f64, f64), c: [u8; 3]) {
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
        for k in 0..=n {
            let t = k as f64 / n as f64;
            self.put(
                (a.0 + t * (b.0 - a.0)) as i64,
                (a.1 + t * (b.1 - a.1)) as i64,
                c,
            );
        }
    }

    fn world_line(&mut self, a: [f64; 2], b: [f64; 2], c: [u8; 3]) {
        let (a, b) = (self.to_px(a), self.to_px(b));
        self.line(a, b, c);
    }

    /// The 2-sigma ellipse of covariance `cov` around `m`.
    fn ellipse(&mut self, m: [f64; 2], cov: [[f64; 2]; 2], c: [u8; 3]) {
        let (a, b, d) = (cov[0][0], cov[0][1], cov[1][1]);
        let l1 = asm::pf::max_eigenvalue(cov);
        let l2 = (a + d - l1).max(0.0);
        let ang = 0.5 * (2.0 * b).atan2(a - d);
        let (r1, r2) = (2.0 * l1.sqrt(), 2.0 * l2.sqrt());
        let pts: Vec<[f64; 2]> = (0..=72)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 72.0;
                let (x, y) = (r1 * t.cos(), r2 * t.sin());
                [
                    m[0] + x * ang.cos() - y * ang.sin(),
                    m[1] + x * ang.sin() + y * ang.cos(),
                ]
            })
            .collect();
        for w in pts.windows(2) {
            self.world_line(w[0], w[1], c);
        }
    }
}

/// Draws the map picture and writes it to `path`.
///
/// # Errors
/// If the file cannot be written.
pub fn write_png(
    path: &Path,
    map: &OccupancyMap,
    poses: &[Pose],
    result: &MapResult,
    truth: Option<&[[f64; 2]]>,
) -> Result<()> {
    let (w, h) = (map.width() * SCALE, map.height() * SCALE);
    let mut cv = Canvas {
        w,
        h,
        rgb: vec![0; w * h * 3],
        map,
    };
    for j in 0..map.height() {
        for i in 0..map.width() {
            let v = match map.cell(i, j) {
                Cell::Free => 250,
                Cell::Occupied => 40,
                Cell::Unknown => 190,
            };
            for y in j * SCALE..(j + 1) * SCALE {
                for x in i * SCALE..(i + 1) * SCALE {
                    cv.put(x as i64, y as i64, [v, v, v]);
                }
            }
        }
    }
    for (k, s) in result.sources.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        for p in &s.cluster {
            cv.disk(*p, 0.8, c);
        }
    }
    let path_c = [40, 70, 200];
    for win in poses.windows(2) {
        cv.world_line([win[0].x, win[0].y], [win[1].x, win[1].y], path_c);
    }
    for p in poses {
        cv.disk([p.x, p.y], 2.5, path_c);
        // Heading tick, 0.15 m long.
        cv.world_line(
            [p.x, p.y],
            [p.x + 0.15 * p.theta.cos(), p.y + 0.15 * p.theta.sin()],
            path_c,
        );
    }
    if let Some(truth) = truth {
        for t in truth {
            let (cx, cy) = cv.to_px(*t);
            let r = 0.12 / map.resolution() * SCALE as f64;
            for k in 0..48 {
                let a = std::f64::consts::TAU * k as f64 / 48.0;
                let b = std::f64::consts::TAU * (k + 1) as f64 / 48.0;
                cv.line(
                    (cx + r * a.cos(), cy + r * a.sin()),
                    (cx + r * b.cos(), cy + r * b.sin()),
                    [0, 150, 0],
                );
            }
        }
    }
    let red = [220, 20, 20];
    for s in &result.sources {
        cv.ellipse([s.x, s.y], s.covariance, red);
        let (cx, cy) = cv.to_px([s.x, s.y]);
        for d in -5i64..=5 {
            for t in 0..2 {
                cv.put(cx as i64 + d + t, cy as i64 + d, red);
                cv.put(cx as i64 + d + t, cy as i64 - d, red);
            }
        }
    }
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc
        .write_header()
        .with_context(|| format!("writing {}", path.display()))?;
    wr.write_image_data(&cv.rgb)
        .with_context(|| format!("writing {}", path.display()))?;
    wr.finish()
        .with_context(|| format!("writing {}", path.display()))?;
    crate::output::write_atomic(path, &bytes)
}
