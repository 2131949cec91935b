//! A structural check of JPEG data before it is decoded.
//!
//! JPEG decoders are lenient: data cut short decodes "successfully", the missing rows
//! grey, and a few hundred bytes whose header claims 16000 × 16000 pixels cost
//! gigabytes and half a minute before giving a flat picture. [`check`] walks the
//! markers (segment lengths; after each start-of-scan, the entropy-coded data, in
//! which `FF 00` stuffing and the restart markers `FF D0`–`FF D7` are data) and
//! refuses data that ends before its end-of-image marker, or whose first scan is too
//! short for the size the frame header claims. It reads every byte once and
//! allocates nothing.

/// Why JPEG data is refused before decoding.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum JpegProblem {
    /// The data ends before the end-of-image marker.
    Truncated,
    /// The first scan holds fewer bytes than the pixels it codes need.
    TooShort {
        /// Width the frame header claims.
        width: u32,
        /// Height the frame header claims.
        height: u32,
    },
}

impl JpegProblem {
    /// The problem as the detail of a [`RenderError::Corrupt`](crate::RenderError).
    pub(crate) fn detail(&self) -> String {
        match self {
            Self::Truncated => "truncated: the JPEG ends before its end-of-image marker".into(),
            Self::TooShort { width, height } => {
                format!("its data is too short for {width}×{height} pixels")
            }
        }
    }
}

/// A frame header (SOFn): what the scans code.
struct Frame {
    width: u32,
    height: u32,
    /// Huffman-coded (SOF0–3, SOF5–7) rather than arithmetic-coded.
    huffman: bool,
    /// Component id and sampling factors (horizontal, vertical).
    components: Vec<(u8, u32, u32)>,
}

impl Frame {
    fn parse(marker: u8, body: &[u8]) -> Option<Self> {
        let be16 = |at: usize| {
            Some(u32::from(u16::from_be_bytes([
                *body.get(at)?,
                *body.get(at + 1)?,
            ])))
        };
        let height = be16(1)?;
        let width = be16(3)?;
        let count = usize::from(*body.get(5)?);
        let components = (0..count)
            .map(|k| {
                let at = 6 + 3 * k;
                let sampling = *body.get(at + 1)?;
                Some((
                    *body.get(at)?,
                    u32::from(sampling >> 4),
                    u32::from(sampling & 15),
                ))
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Self {
            width,
            height,
            huffman: marker < 0xC8,
            components,
        })
    }

    /// The fewest bytes a Huffman-coded first scan of the components `ids` can take.
    ///
    /// Every 8 × 8 block of every component in a scan starts with its DC difference
    /// (the whole DC in a sequential scan, its high bits in a progressive DC scan,
    /// which must come before any AC scan of the component), coded with a Huffman
    /// code of at least one bit. A component sampled at `h/h_max`, `v/v_max` has
    /// `ceil(ceil(width·h/h_max)/8) · ceil(ceil(height·v/v_max)/8)` blocks (a scan
    /// of several components codes more, padded to whole MCUs), so the scan holds at
    /// least `ceil(Σ blocks / 8)` bytes. Stuffing, padding and restart markers only
    /// add to that, and they are counted with the data, so the bound never refuses a
    /// complete file. (A lossless frame codes at least a bit per sample, which is more.)
    fn min_scan_bytes(&self, ids: &[u8]) -> u64 {
        let h_max = self
            .components
            .iter()
            .map(|c| c.1)
            .max()
            .unwrap_or(1)
            .max(1);
        let v_max = self
            .components
            .iter()
            .map(|c| c.2)
            .max()
            .unwrap_or(1)
            .max(1);
        let blocks: u64 = self
            .components
            .iter()
            .filter(|c| ids.contains(&c.0))
            .map(|&(_, h, v)| {
                let w = (u64::from(self.width) * u64::from(h)).div_ceil(u64::from(h_max));
                let rows = (u64::from(self.height) * u64::from(v)).div_ceil(u64::from(v_max));
                w.div_ceil(8) * rows.div_ceil(8)
            })
            .sum();
        blocks.div_ceil(8)
    }
}

/// Walks the markers of JPEG data (starting with `FF D8`) up to its end-of-image
/// marker; see the module documentation.
///
/// Data it cannot make sense of otherwise (a bad segment length, garbage between
/// segments) is left to the decoder to judge.
pub(crate) fn check(bytes: &[u8]) -> Result<(), JpegProblem> {
    let mut frame: Option<Frame> = None;
    let mut first_scan = true;
    let mut i = 2;
    loop {
        // Find the next marker, skipping stray bytes and fill bytes.
        let Some(at) = bytes
            .get(i..)
            .and_then(|rest| rest.iter().position(|&b| b == 0xFF))
        else {
            return Err(JpegProblem::Truncated);
        };
        i += at;
        while bytes.get(i) == Some(&0xFF) {
            i += 1;
        }
        let Some(&marker) = bytes.get(i) else {
            return Err(JpegProblem::Truncated);
        };
        i += 1;
        match marker {
            0xD9 => return Ok(()),
            // Standalone markers: start of image, TEM, restarts; and stuffing out of place.
            0x00 | 0x01 | 0xD0..=0xD8 => continue,
            _ => {}
        }
        let Some(&[hi, lo]) = bytes.get(i..i + 2) else {
            return Err(JpegProblem::Truncated);
        };
        let length = usize::from(u16::from_be_bytes([hi, lo]));
        if length < 2 {
            return Ok(());
        }
        let Some(body) = bytes.get(i + 2..i + length) else {
            return Err(JpegProblem::Truncated);
        };
        i += length;
        match marker {
            // The first frame header (a hierarchical file has more).
            0xC0..=0xCF if !matches!(marker, 0xC4 | 0xC8 | 0xCC) && frame.is_none() => {
                frame = Frame::parse(marker, body);
            }
            0xDA => {
                let start = i;
                let mut restarts = 0;
                // The entropy-coded data runs to the next marker that is neither
                // stuffing (FF 00) nor a restart (FF D0-D7).
                loop {
                    let Some(at) = bytes
                        .get(i..)
                        .and_then(|r| r.iter().position(|&b| b == 0xFF))
                    else {
                        return Err(JpegProblem::Truncated);
                    };
                    i += at;
                    match bytes.get(i + 1) {
                        None => return Err(JpegProblem::Truncated),
                        Some(0x00) => i += 2,
                        Some(0xD0..=0xD7) => {
                            restarts += 2;
                            i += 2;
                        }
                        // A fill byte: look again from the next one.
                        Some(0xFF) => i += 1,
                        Some(_) => break,
                    }
                }
                if std::mem::take(&mut first_scan)
                    && let Some(frame) = &frame
                    && frame.huffman
                    && frame.height > 0
                {
                    let count = usize::from(body.first().copied().unwrap_or(0));
                    let ids: Vec<u8> = (0..count)
                        .filter_map(|k| body.get(1 + 2 * k).copied())
                        .collect();
                    let data = (i - start - restarts) as u64;
                    if data < frame.min_scan_bytes(&ids) {
                        return Err(JpegProblem::TooShort {
                            width: frame.width,
                            height: frame.height,
                        });
                    }
                }
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(width: u32, height: u32, seed: u32) -> Vec<u8> {
        let image = image::RgbImage::from_fn(width, height, |x, y| {
            let v = (x * 7 + y * 13 + seed) as u8;
            image::Rgb([v, v.wrapping_mul(3), 255 - v])
        });
        let mut bytes = std::io::Cursor::new(Vec::new());
        image
            .write_to(&mut bytes, image::ImageFormat::Jpeg)
            .expect("encode");
        bytes.into_inner()
    }

    #[test]
    fn whole_files_pass() {
        for (w, h) in [(1, 1), (8, 8), (37, 21), (300, 200)] {
            assert_eq!(check(&encode(w, h, w + h)), Ok(()), "{w}x{h}");
        }
    }

    #[test]
    fn every_cut_is_truncated() {
        let whole = encode(40, 30, 1);
        for cut in 2..whole.len() - 1 {
            assert!(
                check(&whole[..cut]).is_err(),
                "cut at {cut} of {}",
                whole.len()
            );
        }
    }

    #[test]
    fn a_header_claiming_more_than_the_data_holds_is_too_short() {
        let mut forged = encode(16, 16, 2);
        // The SOF0 segment: FF C0, length, precision, height, width.
        let sof = forged
            .windows(2)
            .position(|w| w == [0xFF, 0xC0])
            .expect("a baseline frame header");
        forged[sof + 5..sof + 7].copy_from_slice(&16000u16.to_be_bytes());
        forged[sof + 7..sof + 9].copy_from_slice(&16000u16.to_be_bytes());
        assert_eq!(
            check(&forged),
            Err(JpegProblem::TooShort {
                width: 16000,
                height: 16000
            })
        );
    }

    #[test]
    fn stuffing_and_restarts_are_data() {
        // A hand-made file: SOI, a 16×8 single-component Huffman frame, a scan
        // whose data holds FF 00 and a restart marker, EOI.
        let mut bytes = vec![0xFF, 0xD8];
        bytes.extend([0xFF, 0xC0, 0, 11, 8, 0, 8, 0, 16, 1, 1, 0x11, 0]);
        bytes.extend([0xFF, 0xDA, 0, 8, 1, 1, 0, 0, 63, 0]);
        bytes.extend([0x12, 0xFF, 0x00, 0xFF, 0xD3, 0x34]);
        bytes.extend([0xFF, 0xD9]);
        assert_eq!(check(&bytes), Ok(()));
        // Two blocks need one byte; an empty scan is too short.
        let mut empty = bytes.clone();
        empty.drain(bytes.len() - 8..bytes.len() - 2);
        assert_eq!(
            check(&empty),
            Err(JpegProblem::TooShort {
                width: 16,
                height: 8
            })
        );
        // No end-of-image marker after the scan.
        assert_eq!(
            check(&bytes[..bytes.len() - 2]),
            Err(JpegProblem::Truncated)
        );
    }
}
