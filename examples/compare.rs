//! Error of a rendered image against a reference, both linear (PFM or EXR):
//! `cargo run --release --example compare -- REFERENCE IMAGE`.
//!
//! Prints the mean relative squared error, mean((x - r)^2 / (r^2 + 0.01)) over
//! pixels and channels (the epsilon keeps black pixels from dominating, as in
//! Rousselle et al. 2011), the root mean squared error, and the ratio of mean
//! luminances (image / reference). RMSE and the luminance ratio leave out the
//! pixels where the reference is brighter than 10 (the light itself: its
//! radiance, ~111 in `cornell`, would otherwise outweigh the whole room).

use raytracer::image_io::read_image;
use raytracer::math::luminance;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 2 {
        eprintln!("usage: compare REFERENCE IMAGE (linear .pfm or .exr)");
        return ExitCode::from(2);
    }
    let (r, x) = match (read_image(Path::new(&args[0])), read_image(Path::new(&args[1]))) {
        (Ok(r), Ok(x)) => (r, x),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    if (r.width, r.height) != (x.width, x.height) {
        eprintln!(
            "error: sizes differ: {}x{} and {}x{}",
            r.width, r.height, x.width, x.height
        );
        return ExitCode::from(2);
    }
    let (mut rel, mut sq, mut lr, mut lx, mut kept) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    for (a, b) in r.pixels.iter().zip(&x.pixels) {
        let light = luminance(*a) > 10.0;
        for (ra, xb) in a.to_array().into_iter().zip(b.to_array()) {
            let d = (xb - ra) as f64;
            rel += d * d / (ra as f64 * ra as f64 + 0.01);
            if !light {
                sq += d * d;
            }
        }
        if !light {
            lr += luminance(*a) as f64;
            lx += luminance(*b) as f64;
            kept += 1;
        }
    }
    println!(
        "relMSE {:.6}  RMSE {:.6}  luminance ratio {:.4}  ({} light pixels left out)",
        rel / (r.pixels.len() * 3) as f64,
        (sq / (kept * 3).max(1) as f64).sqrt(),
        lx / lr,
        r.pixels.len() - kept
    );
    ExitCode::SUCCESS
}
