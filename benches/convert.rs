//! Conversion throughput: envmaps/sunrise.exr (1024x512) to 81 bands, half, exact mode with the
//! sun off (the work `tools/bench_convert.py` compares with Python), at ZIP, ZIPS, PIZ and no
//! compression, and the faithful default at ZIP; `inspect` (read, the scene's analysis and the
//! plan's measure of every pixel, no file: what the default conversion does before it writes);
//! then the encoder alone: libdeflate at level 4
//! compressing the very blocks of the ZIP output (inflated back from the file: the predictor's
//! bytes as the writer gave them), on the same threads. The encoder's share of a conversion's
//! wall time is the second's time over the first's (`cargo bench --bench convert`).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use exr::block::chunk::CompressedBlock;
use rayon::prelude::*;
use specmap::envmap::convert::{convert, inspect, ConvertOptions, LightSpec};
use specmap::envmap::files::zip::ZipEncoder;
use specmap::envmap::files::Compression;
use specmap::fit::Mode;
use std::path::Path;
use std::time::Duration;

fn exact(compression: Compression) -> ConvertOptions {
    ConvertOptions {
        mode: Mode::Exact,
        light: LightSpec::Named("D65".into()),
        sun: None,
        compression,
        ..ConvertOptions::default()
    }
}

/// The uncompressed bytes of every ZIP block of a file written by specmap (half samples), as
/// they were handed to libdeflate: split and predicted.
fn predicted_blocks(path: &Path) -> Vec<Vec<u8>> {
    let file = std::io::BufReader::new(std::fs::File::open(path).expect("the output"));
    let reader = exr::block::read(file, false).expect("an EXR");
    let header = &reader.meta_data().headers[0];
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    let channels = header.channels.list.len();
    let mut inflate = libdeflater::Decompressor::new();
    let mut blocks = Vec::new();
    for chunk in reader.all_chunks(false).expect("chunks") {
        let CompressedBlock::ScanLine(b) = chunk.expect("a chunk").compressed_block else {
            panic!("scan lines expected");
        };
        let lines = 16.min(height - b.y_coordinate as usize);
        let n = lines * width * channels * 2;
        let mut raw = vec![0u8; n];
        if b.compressed_pixels_le.len() < n {
            let got = inflate
                .zlib_decompress(&b.compressed_pixels_le, &mut raw)
                .expect("zlib data");
            assert_eq!(got, n);
        } else {
            raw = b.compressed_pixels_le;
        }
        blocks.push(raw);
    }
    blocks
}

fn bench(c: &mut Criterion) {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("envmaps/sunrise.exr");
    let input = input.to_str().expect("a UTF-8 path").to_string();
    let dir = tempfile::tempdir().expect("a temporary folder");
    let out = dir.path().join("out.exr");
    let mut g = c.benchmark_group("convert sunrise 1024x512 81 bands half");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.throughput(Throughput::Elements(1024 * 512));
    let cases = [
        ("exact zip", exact(Compression::Zip)),
        ("exact zips", exact(Compression::Zips)),
        ("exact piz", exact(Compression::Piz)),
        ("exact none", exact(Compression::None)),
        (
            "faithful zip",
            ConvertOptions {
                compression: Compression::Zip,
                ..ConvertOptions::faithful()
            },
        ),
    ];
    for (name, opts) in &cases {
        g.bench_with_input(BenchmarkId::from_parameter(name), opts, |b, opts| {
            b.iter(|| convert(&input, &out, opts, &|_, _| {}).expect("converts"))
        });
    }
    g.bench_function("inspect (faithful: read, analyse, plan)", |b| {
        b.iter(|| inspect(&input, &ConvertOptions::faithful()).expect("inspects"))
    });
    g.finish();

    // The encoder alone on the exact ZIP output's own blocks, in parallel as the writer runs it.
    convert(&input, &out, &exact(Compression::Zip), &|_, _| {}).expect("converts");
    let blocks = predicted_blocks(&out);
    let bytes: usize = blocks.iter().map(Vec::len).sum();
    let mut g = c.benchmark_group("encoder alone: the exact zip output's blocks");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.throughput(Throughput::Bytes(bytes as u64));
    g.bench_function("libdeflate level 4, all threads", |b| {
        b.iter(|| {
            blocks
                .par_iter()
                .map_init(
                    || {
                        let level = libdeflater::CompressionLvl::new(4).expect("a level");
                        (libdeflater::Compressor::new(level), Vec::new())
                    },
                    |(z, buf), block| {
                        buf.resize(z.zlib_compress_bound(block.len()), 0);
                        z.zlib_compress(block, buf).expect("compresses")
                    },
                )
                .sum::<usize>()
        })
    });
    g.finish();

    // One 16-line block of the same output through the whole ZIP encoding (predictor + zlib).
    let mut g = c.benchmark_group("zip block 16 lines x 1024 x 85 half");
    g.sample_size(20).measurement_time(Duration::from_secs(3));
    // The predictor undone: the block as the writer lays it out before encoding.
    let mut block = blocks[blocks.len() / 2].clone();
    for i in 1..block.len() {
        block[i] = block[i - 1].wrapping_add(block[i]).wrapping_sub(128);
    }
    let block = &block;
    g.throughput(Throughput::Bytes(block.len() as u64));
    for level in [4u8, 1] {
        let mut enc = ZipEncoder::new(level);
        g.bench_with_input(BenchmarkId::new("level", level), block, |b, block| {
            b.iter(|| enc.encode_split(block))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
