//! A recorded camera: `sensor_msgs/Image` (`mono8`, `bgr8`, `rgb8`),
//! `sensor_msgs/CompressedImage` (PNG, JPEG, decoded by the `image` crate)
//! and `sensor_msgs/CameraInfo`, and a stereo pair's image topics read
//! from a bag ([`read_stereo`]) as grey images.
//!
//! A message that cannot become a grey image (a truncated buffer, a size
//! or step that disagrees with its data, an encoding gpodo does not read, a
//! compressed stream that does not decode) is an [`ImageError`] naming the
//! topic, the message's stamp and what was expected; nothing panics.

use std::path::Path;

use gpodo_vision::GrayImage;
use serde::{Deserialize, Serialize};

use super::OnDamage;
pub use super::messages::{CameraInfo, CompressedImage, Image};
use super::messages::{Header, RosMessage};
use super::topic::{TopicError, TopicRequest, read_topics};

/// Why a recorded image could not become a grey image.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("topic `{topic}`, message stamped {stamp_secs:.6} s: {detail}")]
pub struct ImageError {
    /// The topic.
    pub topic: String,
    /// The message's header stamp (s since the epoch).
    pub stamp_secs: f64,
    /// What was wrong and what was expected.
    pub detail: String,
}

/// One recorded image, as it was recorded (compressed ones stay so until
/// asked for).
#[derive(Debug, Clone, PartialEq)]
pub enum RecordedImage {
    /// Raw pixels.
    Raw(Image),
    /// A compressed stream.
    Compressed(CompressedImage),
}

impl RecordedImage {
    /// The header.
    pub fn header(&self) -> &Header {
        match self {
            Self::Raw(i) => &i.header,
            Self::Compressed(c) => &c.header,
        }
    }

    /// The image in grey levels (colour as ITU-R BT.601 luma, rounded).
    ///
    /// # Errors
    /// [`ImageError`] naming `topic`, the stamp and what was expected.
    pub fn to_gray(&self, topic: &str) -> Result<GrayImage, ImageError> {
        let fail = |detail: String| ImageError {
            topic: topic.into(),
            stamp_secs: self.header().stamp_ns as f64 * 1e-9,
            detail,
        };
        match self {
            Self::Raw(image) => raw_to_gray(image).map_err(fail),
            Self::Compressed(c) => compressed_to_gray(c).map_err(fail),
        }
    }
}

/// Grey levels of BT.601 luma from 8-bit red, green and blue.
fn luma(r: u8, g: u8, b: u8) -> u8 {
    let y = (299 * u32::from(r) + 587 * u32::from(g) + 114 * u32::from(b) + 500) / 1000;
    y.min(255) as u8
}

fn raw_to_gray(image: &Image) -> Result<GrayImage, String> {
    let channels = match image.encoding.as_str() {
        "mono8" | "8UC1" => 1,
        "bgr8" | "rgb8" => 3,
        other => {
            return Err(format!("encoding `{other}`, expected mono8, bgr8 or rgb8"));
        }
    };
    let (w, h, step) = (
        image.width as usize,
        image.height as usize,
        image.step as usize,
    );
    if w == 0 || h == 0 {
        return Err(format!(
            "an image of {w} × {h} pixels, expected at least 1 × 1"
        ));
    }
    if step < w * channels {
        return Err(format!(
            "a step of {step} bytes, expected at least {} for {w} {} pixels",
            w * channels,
            image.encoding
        ));
    }
    let needed = step * (h - 1) + w * channels;
    if image.data.len() < needed {
        return Err(format!(
            "{} bytes of pixels, expected {} ({h} rows of {step} bytes): truncated",
            image.data.len(),
            step * h
        ));
    }
    let mut pixels = Vec::with_capacity(w * h);
    for row in image.data.chunks(step).take(h) {
        let row = &row[..w * channels];
        match image.encoding.as_str() {
            "bgr8" => pixels.extend(row.chunks_exact(3).map(|p| luma(p[2], p[1], p[0]))),
            "rgb8" => pixels.extend(row.chunks_exact(3).map(|p| luma(p[0], p[1], p[2]))),
            _ => pixels.extend_from_slice(row),
        }
    }
    GrayImage::from_pixels(w, h, pixels).map_err(|e| e.to_string())
}

fn compressed_to_gray(c: &CompressedImage) -> Result<GrayImage, String> {
    let format = c.format.to_ascii_lowercase();
    let expected = if format.contains("png") {
        image::ImageFormat::Png
    } else if format.contains("jpeg") || format.contains("jpg") {
        image::ImageFormat::Jpeg
    } else {
        return Err(format!("format `{}`, expected png or jpeg", c.format));
    };
    let decoded = image::load_from_memory_with_format(&c.data, expected).map_err(|e| {
        format!(
            "a {} stream of {} bytes that does not decode: {e}",
            c.format,
            c.data.len()
        )
    })?;
    let grey = decoded.to_luma8();
    let (w, h) = (grey.width() as usize, grey.height() as usize);
    GrayImage::from_pixels(w, h, grey.into_raw()).map_err(|e| e.to_string())
}

/// The image and camera-info topics of a recorded stereo camera (a topic
/// map's `camera:`). The images must be rectified; their stamps pair
/// them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraTopics {
    /// The left image (`sensor_msgs/Image` or `CompressedImage`).
    pub left: String,
    /// The right image.
    pub right: String,
    /// The left camera's `sensor_msgs/CameraInfo` (optional).
    #[serde(default)]
    pub left_info: Option<String>,
    /// The right camera's `sensor_msgs/CameraInfo` (optional: gives the
    /// baseline from its projection matrix).
    #[serde(default)]
    pub right_info: Option<String>,
}

/// A recorded stereo camera: its left and right images paired by stamp,
/// and the first camera-info messages.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoRecording {
    /// The topics.
    pub topics: CameraTopics,
    /// `(stamp_ns, left, right)` for each stamp both images have, in time
    /// order.
    pub pairs: Vec<(i64, RecordedImage, RecordedImage)>,
    /// Left images whose stamp no right image has.
    pub unpaired: usize,
    /// The first left and right `CameraInfo`, when their topics are given.
    pub info: [Option<CameraInfo>; 2],
}

impl StereoRecording {
    /// The rectified pair nearest to `stamp_ns`, within `tolerance_ns`, in
    /// grey levels.
    ///
    /// # Errors
    /// A message naming the time when no pair is that close, or an
    /// [`ImageError`]'s message.
    pub fn gray_pair_near(
        &self,
        stamp_ns: i64,
        tolerance_ns: i64,
    ) -> Result<(GrayImage, GrayImage), String> {
        let k = self.pairs.partition_point(|(t, _, _)| *t < stamp_ns);
        let nearest = [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter_map(|i| self.pairs.get(i))
            .min_by_key(|(t, _, _)| (t - stamp_ns).abs());
        let Some((t, left, right)) =
            nearest.filter(|(t, _, _)| (t - stamp_ns).abs() <= tolerance_ns)
        else {
            return Err(format!(
                "no stereo pair on `{}` and `{}` within {:.3} s of {:.6} s",
                self.topics.left,
                self.topics.right,
                tolerance_ns as f64 * 1e-9,
                stamp_ns as f64 * 1e-9
            ));
        };
        let l = left.to_gray(&self.topics.left).map_err(|e| e.to_string())?;
        let r = right
            .to_gray(&self.topics.right)
            .map_err(|e| e.to_string())?;
        if (l.width(), l.height()) != (r.width(), r.height()) {
            return Err(format!(
                "the pair stamped {:.6} s: left is {}×{} but right {}×{}, expected one size",
                *t as f64 * 1e-9,
                l.width(),
                l.height(),
                r.width(),
                r.height()
            ));
        }
        Ok((l, r))
    }
}

/// The types an image topic may have.
pub const IMAGE_TYPES: [&str; 2] = ["sensor_msgs/Image", "sensor_msgs/CompressedImage"];

/// The stereo camera of `topics` in the bag at `path`: both image topics
/// and the camera-info topics given, in one pass.
///
/// # Errors
/// [`TopicError`] naming the file, topic, type and message index.
pub fn read_stereo(
    path: &Path,
    topics: &CameraTopics,
    on_damage: OnDamage,
) -> Result<StereoRecording, TopicError> {
    let info_types = ["sensor_msgs/CameraInfo"];
    let mut requests = vec![
        TopicRequest {
            topic: &topics.left,
            role: "camera.left",
            expected: &IMAGE_TYPES,
            optional: false,
        },
        TopicRequest {
            topic: &topics.right,
            role: "camera.right",
            expected: &IMAGE_TYPES,
            optional: false,
        },
    ];
    for (topic, role) in [
        (&topics.left_info, "camera.left_info"),
        (&topics.right_info, "camera.right_info"),
    ] {
        if let Some(topic) = topic {
            requests.push(TopicRequest {
                topic,
                role,
                expected: &info_types,
                optional: false,
            });
        }
    }
    let (mut read, _) = read_topics(path, &requests, on_damage)?;
    let images = |messages: Vec<super::topic::Stamped>| -> Vec<RecordedImage> {
        let mut v: Vec<RecordedImage> = messages
            .into_iter()
            .filter_map(|m| match m.message {
                RosMessage::Image(i) => Some(RecordedImage::Raw(i)),
                RosMessage::CompressedImage(c) => Some(RecordedImage::Compressed(c)),
                _ => None,
            })
            .collect();
        v.sort_by_key(|i| i.header().stamp_ns);
        v
    };
    let mut infos = read.split_off(2).into_iter().map(|messages| {
        messages.into_iter().find_map(|m| match m.message {
            RosMessage::CameraInfo(c) => Some(c),
            _ => None,
        })
    });
    let mut info = [None, None];
    if topics.left_info.is_some() {
        info[0] = infos.next().flatten();
    }
    if topics.right_info.is_some() {
        info[1] = infos.next().flatten();
    }
    let right_messages = read.pop().unwrap_or_default();
    let left_messages = read.pop().unwrap_or_default();
    let (left, right) = (images(left_messages), images(right_messages));
    let mut pairs = Vec::with_capacity(left.len());
    let mut unpaired = 0;
    let mut rights = right.into_iter().peekable();
    for l in left {
        let t = l.header().stamp_ns;
        while rights.peek().is_some_and(|r| r.header().stamp_ns < t) {
            rights.next();
        }
        match rights.next_if(|r| r.header().stamp_ns == t) {
            Some(r) => pairs.push((t, l, r)),
            None => unpaired += 1,
        }
    }
    Ok(StereoRecording {
        topics: topics.clone(),
        pairs,
        unpaired,
        info,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        Header {
            stamp_ns: 1_500_000_000,
            frame_id: "left".into(),
        }
    }

    fn raw(encoding: &str, w: u32, h: u32, step: u32, data: Vec<u8>) -> RecordedImage {
        RecordedImage::Raw(Image {
            header: header(),
            height: h,
            width: w,
            encoding: encoding.into(),
            is_bigendian: 0,
            step,
            data,
        })
    }

    #[test]
    fn raw_encodings_become_the_same_grey_levels() {
        // Two pixels per row, one padding byte, two rows.
        let mono = raw("mono8", 2, 2, 3, vec![10, 20, 0, 30, 40, 0]);
        let g = mono.to_gray("/cam").unwrap();
        assert_eq!(g.pixels(), &[10, 20, 30, 40]);
        let rgb = raw("rgb8", 1, 1, 3, vec![200, 100, 50]);
        let bgr = raw("bgr8", 1, 1, 3, vec![50, 100, 200]);
        // 0.299·200 + 0.587·100 + 0.114·50 = 124.2
        assert_eq!(rgb.to_gray("/cam").unwrap().pixels(), &[124]);
        assert_eq!(bgr.to_gray("/cam").unwrap().pixels(), &[124]);
    }

    #[test]
    fn bad_images_name_the_topic_the_stamp_and_what_was_expected() {
        let truncated = raw("mono8", 4, 4, 4, vec![0; 10]);
        let e = truncated.to_gray("/stereo/left").unwrap_err();
        assert_eq!(e.topic, "/stereo/left");
        assert!((e.stamp_secs - 1.5).abs() < 1e-12);
        assert!(e.to_string().contains("truncated"), "{e}");
        let short_step = raw("rgb8", 4, 1, 4, vec![0; 12]);
        assert!(
            short_step
                .to_gray("/c")
                .unwrap_err()
                .detail
                .contains("step of 4")
        );
        let depth = raw("16UC1", 1, 1, 2, vec![0; 2]);
        assert!(
            depth
                .to_gray("/c")
                .unwrap_err()
                .detail
                .contains("mono8, bgr8 or rgb8")
        );
        let garbage = RecordedImage::Compressed(CompressedImage {
            header: header(),
            format: "jpeg".into(),
            data: vec![0xff, 0xd8, 0xff, 0x00, 1, 2, 3],
        });
        let e = garbage.to_gray("/c").unwrap_err();
        assert!(e.detail.contains("does not decode"), "{e}");
        let tiff = RecordedImage::Compressed(CompressedImage {
            header: header(),
            format: "tiff".into(),
            data: vec![],
        });
        assert!(
            tiff.to_gray("/c")
                .unwrap_err()
                .detail
                .contains("png or jpeg")
        );
    }

    #[test]
    fn compressed_png_and_jpeg_decode_to_the_image() {
        let (w, h) = (16u32, 8u32);
        let pixels: Vec<u8> = (0..w * h).map(|k| (k * 2) as u8).collect();
        let encode = |format: image::ImageFormat| {
            let mut bytes = std::io::Cursor::new(Vec::new());
            image::GrayImage::from_raw(w, h, pixels.clone())
                .unwrap()
                .write_to(&mut bytes, format)
                .unwrap();
            bytes.into_inner()
        };
        let png = RecordedImage::Compressed(CompressedImage {
            header: header(),
            format: "mono8; png compressed".into(),
            data: encode(image::ImageFormat::Png),
        });
        assert_eq!(png.to_gray("/c").unwrap().pixels(), pixels.as_slice());
        let jpeg = RecordedImage::Compressed(CompressedImage {
            header: header(),
            format: "jpeg".into(),
            data: encode(image::ImageFormat::Jpeg),
        });
        let g = jpeg.to_gray("/c").unwrap();
        assert_eq!((g.width(), g.height()), (16, 8));
        let worst = g
            .pixels()
            .iter()
            .zip(&pixels)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        assert!(worst <= 12, "JPEG off by {worst}");
    }
}
