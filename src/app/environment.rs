//! Loading the scene's environment for the renderer.

use std::path::Path;

use crate::render::Environment;
use crate::scene::EnvironmentChoice;

/// Largest environment image accepted, in texels per side.
const MAX_SIDE: u32 = 8192;
/// Most texels an environment image may have (an 8k × 4k panorama): decoding and converting
/// one takes about 0.9 GB at its peak.
const MAX_TEXELS: u64 = 8192 * 4096;

/// A problem with an environment image; names the file.
#[derive(Debug, thiserror::Error)]
#[error("environment image {path}: {reason}")]
pub struct EnvironmentError {
    /// The image.
    pub path: String,
    /// What is wrong.
    pub reason: String,
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The environment a scene chose: the built-in studio, or an equirectangular image (PNG in
/// sRGB, or Radiance HDR in linear radiance).
pub fn load_environment(choice: &EnvironmentChoice) -> Result<Environment, EnvironmentError> {
    let path = match choice {
        EnvironmentChoice::Studio => return Ok(Environment::Studio),
        EnvironmentChoice::Image(path) => path,
    };
    load_equirect(path)
}

fn load_equirect(path: &Path) -> Result<Environment, EnvironmentError> {
    let fail = |reason: String| EnvironmentError { path: path.display().to_string(), reason };
    // A FIFO or a device would block or never end: only regular files are opened.
    crate::io::text::regular_file(path).map_err(|e| fail(format!("cannot open it: {e}")))?;
    let reader = image::ImageReader::open(path)
        .map_err(|e| fail(format!("cannot open it: {e}")))?
        .with_guessed_format()
        .map_err(|e| fail(format!("cannot read it: {e}")))?;
    let format = reader.format();
    let (width, height) =
        reader.into_dimensions().map_err(|e| fail(format!("not a PNG or HDR image: {e}")))?;
    if width > MAX_SIDE || height > MAX_SIDE || width < 4 || height < 2 {
        return Err(fail(format!("{width}x{height} texels is outside 4x2 ..= {MAX_SIDE}x{MAX_SIDE}")));
    }
    if u64::from(width) * u64::from(height) > MAX_TEXELS {
        return Err(fail(format!(
            "{width}x{height} texels is more than the {MAX_TEXELS} an environment may have (8192x4096); \
             scale it down"
        )));
    }
    if width != 2 * height {
        tracing::warn!("environment image {} is {width}x{height}, not 2:1; it is stretched", path.display());
    }
    let image = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| fail(format!("cannot read it: {e}")))?
        .decode()
        .map_err(|e| fail(format!("cannot decode it: {e}")))?;
    let linear_input = format == Some(image::ImageFormat::Hdr);
    let rgb = image.to_rgb32f();
    let texels = rgb
        .pixels()
        .map(|p| {
            let c = [p[0], p[1], p[2]];
            if linear_input {
                c.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 })
            } else {
                c.map(srgb_to_linear)
            }
        })
        .collect();
    Ok(Environment::Equirect { width, height, texels })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_environments_are_decoded_to_linear() {
        let dir = std::env::temp_dir().join(format!("argile-env-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("env.png");
        image::RgbImage::from_pixel(8, 4, image::Rgb([255, 128, 0])).save(&path).unwrap();
        let Environment::Equirect { width, height, texels } =
            load_environment(&EnvironmentChoice::Image(path.clone())).unwrap()
        else {
            panic!("expected an image")
        };
        assert_eq!((width, height, texels.len()), (8, 4, 32));
        assert!((texels[0][1] - 0.2158).abs() < 1e-3);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_images_are_named() {
        let e = load_environment(&EnvironmentChoice::Image("no/such.hdr".into())).unwrap_err();
        assert!(e.to_string().starts_with("environment image no/such.hdr: cannot open it"), "{e}");
    }

    #[test]
    fn images_too_large_to_hold_and_fifos_are_refused_before_decoding() {
        let dir = std::env::temp_dir().join(format!("argile-env-limits-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.png");
        image::GrayImage::new(8192, 4097).save(&big).unwrap();
        let e = load_environment(&EnvironmentChoice::Image(big.clone())).unwrap_err().to_string();
        assert!(e.contains("8192x4097 texels is more than") && e.contains("scale it down"), "{e}");
        let fifo = dir.join("pipe.png");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let e = load_environment(&EnvironmentChoice::Image(fifo)).unwrap_err().to_string();
        assert!(e.contains("FIFO"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
