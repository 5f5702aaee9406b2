//! 8-bit grey PNG files of layer images, written fast.
//!
//! A layer of a print is mostly dark, and deflating a whole display of zeros costs more than
//! drawing the layer did. So each run of wholly dark rows is written as a deflate block of our
//! own: a literal zero, then copies of 258 bytes from one byte back, two bits each (a block
//! with dynamic codes that has only those symbols), as small as zlib makes such a run. The rows
//! between go through zlib (level 6), one sync-flushed piece each. The result is one
//! ordinary zlib stream in one IDAT chunk: 8-bit grey, no filter, as any PNG reader expects.

use zlib_rs::{Deflate, DeflateFlush};

/// Dark rows in a run shorter than this are deflated with the rows around them.
const DARK_RUN: usize = 4;

/// Deflate's longest copy.
const LONGEST: usize = 258;

/// The zlib checksum's modulus.
const ADLER: u64 = 65521;

/// An 8-bit grey PNG of `image`, `w` × `h` pixels, rows top to bottom.
pub fn encode_grey(image: &[u8], w: u32, h: u32) -> Vec<u8> {
    let (width, height) = (w as usize, h as usize);
    assert_eq!(image.len(), width * height, "image size");
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().expect("PNG header into memory");
        writer
            .write_chunk(png::chunk::IDAT, &zlib_rows(image, width, height))
            .expect("PNG data into memory");
        writer.finish().expect("PNG end into memory");
    }
    out
}

/// The zlib stream of the image's rows, each led by its filter byte (0, none).
fn zlib_rows(image: &[u8], width: usize, height: usize) -> Vec<u8> {
    // Bytes or'ed 64 at a time (which vectorises), stopping at the first lit block.
    let dark: Vec<bool> = image
        .chunks_exact(width.max(1))
        .map(|row| row.chunks(64).all(|c| c.iter().fold(0, |m, &b| m | b) == 0))
        .collect();
    // How many dark rows from row r on.
    let dark_from = |r: usize| dark[r..].iter().take_while(|&&d| d).count();
    let mut z = Stream::new();
    let mut rows = Vec::new();
    let mut zlib: Option<Deflate> = None;
    let mut r = 0;
    while r < height {
        let run = dark_from(r);
        if run >= DARK_RUN {
            z.zeros(run * (width + 1));
            r += run;
            continue;
        }
        let mut end = r;
        while end < height {
            let run = dark_from(end);
            if run >= DARK_RUN {
                break;
            }
            end += run.max(1);
        }
        rows.clear();
        for row in image[r * width..end * width].chunks_exact(width.max(1)) {
            rows.push(0);
            rows.extend_from_slice(row);
        }
        let zlib = zlib.get_or_insert_with(|| Deflate::new(6, false, 15));
        z.deflated(zlib, &rows);
        r = end;
    }
    z.finish()
}

/// A zlib stream being written: deflate's bits, least significant first, and the checksum.
struct Stream {
    out: Vec<u8>,
    /// Bits not yet in `out`, the first written lowest.
    bits: u64,
    count: u32,
    /// The Adler-32 sums of the bytes so far.
    a: u64,
    b: u64,
}

impl Stream {
    fn new() -> Stream {
        Stream {
            // Deflate, 32 KiB window, no dictionary; 0x7801 is a multiple of 31.
            out: vec![0x78, 0x01],
            bits: 0,
            count: 0,
            a: 1,
            b: 0,
        }
    }

    /// The `n` low bits of `value`, lowest first (deflate's header fields and extra bits).
    fn put(&mut self, value: u64, n: u32) {
        debug_assert!(n <= 32 && value < 1 << n);
        self.bits |= value << self.count;
        self.count += n;
        while self.count >= 8 {
            self.out.push(self.bits as u8);
            self.bits >>= 8;
            self.count -= 8;
        }
    }

    /// A Huffman code of `n` bits, its highest bit first.
    fn code(&mut self, code: u64, n: u32) {
        let reversed = (0..n).fold(0, |r, i| r | ((code >> i) & 1) << (n - 1 - i));
        self.put(reversed, n);
    }

    /// `n` zero bits.
    fn zero_bits(&mut self, n: usize) {
        let head = n.min(((8 - self.count) % 8) as usize);
        self.put(0, head as u32);
        let n = n - head;
        // Either nothing is left or the stream is at a byte boundary.
        self.out.resize(self.out.len() + n / 8, 0);
        self.put(0, (n % 8) as u32);
    }

    /// Pads to the next byte with zero bits.
    fn align(&mut self) {
        if self.count > 0 {
            self.put(0, 8 - self.count);
        }
    }

    /// `n` zero bytes (n ≥ 1) as one block with dynamic codes for only three symbols: the
    /// literal 0 ('10'), the end of the block ('11') and a copy of 258 ('0'), whose distance
    /// codes are 1 ('0') and 2 ('1', unused).
    fn zeros(&mut self, n: usize) {
        debug_assert!(n >= 1);
        self.put(0, 1); // not the last block
        self.put(2, 2); // dynamic codes
        self.put(286 - 257, 5); // literal/length codes 0..=285
        self.put(2 - 1, 5); // distance codes 0 and 1
        self.put(18 - 4, 4); // code length codes given, in deflate's order, up to the one for 1
        const ORDER: [usize; 18] = [16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1];
        for symbol in ORDER {
            let length = match symbol {
                18 => 1,
                1 | 2 => 2,
                _ => 0,
            };
            self.put(length, 3);
        }
        // The code lengths, by the code length codes: 18 '0' (a run of 11 to 138 zeros, 7
        // extra bits), 1 '10', 2 '11'.
        let (one, two) = (
            |z: &mut Stream| z.code(0b10, 2),
            |z: &mut Stream| z.code(0b11, 2),
        );
        let zero_run = |z: &mut Stream, run: u64| {
            z.code(0, 1);
            z.put(run - 11, 7);
        };
        two(self); // literal 0
        zero_run(self, 138); // literals 1..=138
        zero_run(self, 117); // literals 139..=255
        two(self); // end of block (256)
        zero_run(self, 28); // lengths 257..=284
        one(self); // length 258 (285)
        one(self); // distance 1 (code 0)
        one(self); // distance 2 (code 1)

        // The bytes: a literal 0, then copies of 258 bytes from one byte back (length code '0'
        // and distance code '0', no extra bits), the rest as literals.
        self.code(0b10, 2);
        let copies = (n - 1) / LONGEST;
        self.zero_bits(2 * copies);
        for _ in 0..(n - 1) % LONGEST {
            self.code(0b10, 2);
        }
        self.code(0b11, 2);
        // Adler-32 over n zeros: a is unchanged, b grows by n·a.
        self.b = (self.b + (n as u64 % ADLER) * self.a) % ADLER;
    }

    /// `bytes` deflated by `zlib` from a byte boundary, ending at one (a sync flush).
    fn deflated(&mut self, zlib: &mut Deflate, bytes: &[u8]) {
        if self.count > 0 {
            // An empty stored block pads to a byte boundary.
            self.put(0, 3);
            self.align();
            self.out.extend([0x00, 0x00, 0xff, 0xff]);
        }
        zlib.reset();
        let mut fed = 0;
        let mut chunk = vec![0u8; (bytes.len() / 8).clamp(1 << 12, 1 << 20)];
        loop {
            let (before_in, before_out) = (zlib.total_in(), zlib.total_out());
            zlib.compress(&bytes[fed..], &mut chunk, DeflateFlush::SyncFlush)
                .expect("deflate into memory");
            fed += (zlib.total_in() - before_in) as usize;
            let made = (zlib.total_out() - before_out) as usize;
            self.out.extend_from_slice(&chunk[..made]);
            if fed == bytes.len() && made < chunk.len() {
                break;
            }
        }
        let sum = zlib_rs::adler32::adler32(self.checksum(), bytes);
        (self.a, self.b) = ((sum & 0xffff) as u64, (sum >> 16) as u64);
    }

    fn checksum(&self) -> u32 {
        (self.b << 16 | self.a) as u32
    }

    /// The last block (empty, fixed codes), padding, and the checksum.
    fn finish(mut self) -> Vec<u8> {
        self.put(1, 1); // the last block
        self.put(1, 2); // fixed codes
        self.code(0, 7); // end of block (256)
        self.align();
        let sum = self.checksum();
        self.out.extend(sum.to_be_bytes());
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decoded(file: &[u8]) -> (Vec<u8>, u32, u32) {
        let decoder = png::Decoder::new(std::io::Cursor::new(file));
        let mut reader = decoder.read_info().expect("a PNG");
        let mut buf = vec![0; reader.output_buffer_size().expect("size")];
        let info = reader.next_frame(&mut buf).expect("a frame");
        assert_eq!(info.color_type, png::ColorType::Grayscale);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        (buf, info.width, info.height)
    }

    /// The zlib stream inflated by zlib-rs, checksum checked.
    fn inflated(image: &[u8], w: usize, h: usize) -> Vec<u8> {
        let stream = zlib_rows(image, w, h);
        let mut out = vec![0u8; (w + 1) * h + 16];
        let (made, rc) = zlib_rs::decompress_slice(&mut out, &stream, Default::default());
        assert_eq!(rc, zlib_rs::ReturnCode::Ok);
        made.to_vec()
    }

    fn image(w: usize, h: usize, lit: impl Fn(usize, usize) -> u8) -> Vec<u8> {
        (0..h)
            .flat_map(|r| (0..w).map(move |c| (r, c)))
            .map(|(r, c)| lit(r, c))
            .collect()
    }

    #[test]
    fn images_come_back_from_other_readers_unchanged() {
        let cases: Vec<(usize, usize, Vec<u8>)> = vec![
            (1, 1, vec![0]),
            (1, 1, vec![255]),
            (3, 2, vec![0; 6]),
            // Runs of every remainder of 258 around the copies.
            (257, 9, vec![0; 257 * 9]),
            (258, 7, vec![0; 258 * 7]),
            (
                259,
                40,
                image(259, 40, |r, c| (r == 20 && c == 3) as u8 * 200),
            ),
            (
                1920,
                1080,
                image(1920, 1080, |r, c| {
                    if (500..530).contains(&r) && (100..900).contains(&c) {
                        ((r * 7 + c * 3) % 256) as u8
                    } else {
                        0
                    }
                }),
            ),
            // Dark runs at both ends, short ones inside, lit rows at the edges.
            (
                64,
                50,
                image(64, 50, |r, _| {
                    [0, 10, 11, 13, 30, 49].contains(&r) as u8 * 255
                }),
            ),
            (
                5,
                30,
                image(5, 30, |r, c| ((r * 31 + c * 17) % 7 == 0) as u8 * 128),
            ),
        ];
        for (w, h, img) in cases {
            let file = encode_grey(&img, w as u32, h as u32);
            let (back, bw, bh) = decoded(&file);
            assert_eq!((bw as usize, bh as usize), (w, h));
            assert_eq!(back, img, "{w} × {h}");
            let rows: Vec<u8> = img
                .chunks_exact(w)
                .flat_map(|row| std::iter::once(0).chain(row.iter().copied()))
                .collect();
            assert_eq!(inflated(&img, w, h), rows, "{w} × {h}");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 64,
            ..proptest::prelude::ProptestConfig::default()
        })]

        /// Any mix of dark rows (alone, in short and long runs) and rows with a few lit pixels
        /// of any grey, at any width.
        #[test]
        fn any_rows_come_back(
            width in 1usize..700,
            kinds in proptest::collection::vec((0u8..4, 0usize..700, 1u8..=255), 1..80),
        ) {
            let img: Vec<u8> = kinds
                .iter()
                .flat_map(|&(kind, at, grey)| {
                    (0..width).map(move |c| match kind {
                        0 | 1 => 0,
                        2 => (c == at % width) as u8 * grey,
                        _ => ((c * 7 + at) % 5 == 0) as u8 * grey,
                    })
                })
                .collect();
            let h = kinds.len();
            let (back, bw, bh) = decoded(&encode_grey(&img, width as u32, h as u32));
            proptest::prop_assert_eq!((bw as usize, bh as usize), (width, h));
            proptest::prop_assert!(back == img);
            let rows: Vec<u8> = img
                .chunks_exact(width)
                .flat_map(|row| std::iter::once(0).chain(row.iter().copied()))
                .collect();
            proptest::prop_assert!(inflated(&img, width, h) == rows);
        }
    }

    #[test]
    fn a_dark_display_is_a_few_kilobytes() {
        let img = vec![0u8; 1920 * 1080];
        let file = encode_grey(&img, 1920, 1080);
        // 2.07 M zeros at two bits per 258 bytes: about 2 KB.
        assert!(file.len() < 2_500, "{} bytes", file.len());
    }
}
