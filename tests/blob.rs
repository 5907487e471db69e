//! The weight blob: bit-exact round trips, and malformed bytes give the right error,
//! never a panic.

mod support;

use diffbsdf::internals::blob::{blob_len, crc32, write_blob, Blob, CHECKSUM_LEN, HEADER_LEN};
use diffbsdf::{BlobError, Model3x32, Model4x32, ModelName, Precision, TableGrid};
use proptest::prelude::*;
use support::{
    random_disk, random_sphere, random_standardized_half_vector, random_warped_half_vector,
};

fn blob_of(m: &Model3x32, precision: Precision) -> Vec<u8> {
    let mut def = *m.def();
    def.precision = precision;
    let mut out = vec![0u8; blob_len(&def)];
    let n = m.write_blob(precision, &mut out).unwrap();
    assert_eq!(n, out.len());
    out
}

fn params_of(m: &Model3x32) -> Vec<f32> {
    let mut p = vec![0.0; m.def().param_count()];
    m.params(&mut p).unwrap();
    p
}

#[test]
fn f32_round_trip_is_bit_exact() {
    let mut m = random_disk(5, 2);
    m.set_metadata(ModelName::new("cu-ggx-0.3").unwrap(), 4);
    let bytes = blob_of(&m, Precision::F32);
    let back = Model3x32::from_blob(&bytes).unwrap();
    let (a, b) = (params_of(&m), params_of(&back));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert_eq!(back.def().name.as_str(), "cu-ggx-0.3");
    assert_eq!(blob_of(&back, Precision::F32), bytes);
}

#[test]
fn f16_round_trip_is_bit_exact_after_rounding() {
    let m = random_disk(6, 2);
    let bytes = blob_of(&m, Precision::F16);
    let back = Model3x32::from_blob(&bytes).unwrap();
    assert_eq!(back.def().precision, Precision::F16);
    for (w, r) in params_of(&m).iter().zip(params_of(&back)) {
        assert_eq!(half::f16::from_f32(*w).to_f32().to_bits(), r.to_bits());
    }
    assert_eq!(blob_of(&back, Precision::F16), bytes);
    assert_eq!(
        bytes.len(),
        HEADER_LEN + 2 * m.def().param_count() + CHECKSUM_LEN
    );
}

#[test]
fn every_truncation_is_reported_as_truncated() {
    let bytes = blob_of(&random_disk(7, 2), Precision::F16);
    for len in 0..bytes.len() {
        match Model3x32::from_blob(&bytes[..len]) {
            Err(BlobError::Truncated { got, .. }) => assert_eq!(got, len),
            other => panic!("length {len}: {other:?}"),
        }
    }
}

#[test]
fn trailing_bytes_are_rejected() {
    let mut bytes = blob_of(&random_disk(7, 2), Precision::F32);
    bytes.push(0);
    assert!(matches!(
        Model3x32::from_blob(&bytes),
        Err(BlobError::TrailingBytes { .. })
    ));
}

/// The error a flipped bit must give, by where it is.
fn expected_kind(offset: usize, err: &BlobError) -> bool {
    match offset {
        0..=7 => matches!(err, BlobError::BadMagic),
        8..=9 => matches!(err, BlobError::UnsupportedVersion(_)),
        // precision code: another length, or an unknown code
        11 => matches!(
            err,
            BlobError::UnknownPrecision(_)
                | BlobError::Truncated { .. }
                | BlobError::TrailingBytes { .. }
        ),
        // parameter count, and the flags' latent-table bits 4, 5 and 6: another length (or
        // an overflow, a count below the table's, bit 5 without bit 4 or bit 6 without bit
        // 5); the other flag bits are checked behind the checksum
        24..=28 => matches!(
            err,
            BlobError::Truncated { .. }
                | BlobError::TrailingBytes { .. }
                | BlobError::BadHeader(_)
                | BlobError::ChecksumMismatch { .. }
        ),
        _ => matches!(err, BlobError::ChecksumMismatch { .. }),
    }
}

#[test]
fn every_bit_flip_gives_the_error_of_its_region() {
    for precision in [Precision::F32, Precision::F16] {
        let bytes = blob_of(&random_disk(8, 2), precision);
        let mut copy = bytes.clone();
        for offset in 0..bytes.len() {
            for bit in 0..8 {
                copy[offset] ^= 1 << bit;
                let err = Model3x32::from_blob(&copy).expect_err("a flipped bit was accepted");
                assert!(
                    expected_kind(offset, &err),
                    "bit {bit} of byte {offset}: {err:?}"
                );
                copy[offset] ^= 1 << bit;
            }
        }
    }
}

/// Rewrites the checksum after editing a blob, to reach the checks behind it.
fn reseal(bytes: &mut [u8]) {
    let n = bytes.len() - CHECKSUM_LEN;
    let crc = crc32(&bytes[..n]);
    bytes[n..].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn header_errors_behind_a_valid_checksum() {
    let good = blob_of(&random_disk(9, 2), Precision::F32);
    let case = |offset: usize, value: u8| {
        let mut b = good.clone();
        b[offset] = value;
        reseal(&mut b);
        Model3x32::from_blob(&b).unwrap_err()
    };
    assert_eq!(case(10, 7), BlobError::UnknownDomain(7));
    assert_eq!(case(12, 3), BlobError::UnknownActivation(3));
    assert!(matches!(
        case(14, 0),
        BlobError::BadHeader(_) | BlobError::ParamCountMismatch { .. }
    ));
    assert!(matches!(case(16, 0), BlobError::BadHeader(_)));
    assert!(matches!(case(21, 33), BlobError::BadHeader(_)));
    // Default steps (bytes 22..24): 0 and anything above spec::MAX_STEPS are rejected.
    let steps = |n: u16| {
        let mut b = good.clone();
        b[22..24].copy_from_slice(&n.to_le_bytes());
        reseal(&mut b);
        Model3x32::from_blob(&b).map(|m| m.default_steps())
    };
    assert!(matches!(steps(0), Err(BlobError::BadHeader(_))));
    let max = diffbsdf::spec::MAX_STEPS as u16;
    assert_eq!(steps(max), Ok(u32::from(max)));
    assert!(matches!(steps(max + 1), Err(BlobError::BadHeader(_))));
    assert!(matches!(steps(u16::MAX), Err(BlobError::BadHeader(_))));
    // Flags: bit 0 (isotropic), bit 1 (upper hemisphere), bit 2 (standard coordinates),
    // bit 3 (their warp, only with bit 2) and bit 4 (a latent table, only with bit 2) are
    // the only ones defined.
    assert!(matches!(case(28, 8), BlobError::BadHeader(_)));
    assert!(matches!(case(28, 16), BlobError::BadHeader(_)));
    assert_eq!(
        Model3x32::from_blob(&{
            let mut b = good.clone();
            b[28] = 12;
            reseal(&mut b);
            b
        })
        .map(|m| (m.def().standardized, m.def().standard_warp)),
        Ok((true, true))
    );
    assert_eq!(
        Model3x32::from_blob(&{
            let mut b = good.clone();
            b[28] = 4;
            reseal(&mut b);
            b
        })
        .map(|m| m.def().standardized),
        Ok(true)
    );
    assert!(matches!(case(31, 1), BlobError::BadHeader(_)));
    assert!(matches!(case(13, 9), BlobError::BadHeader(_)));
    // A sphere blob has the disk's shape but another domain: the feature count changes
    // the parameter count.
    assert!(matches!(case(10, 1), BlobError::ParamCountMismatch { .. }));
}

/// Standard coordinates exist only on the disk-type domains: a sphere blob with the flag is
/// a header error, and the flag survives a write / read round trip.
#[test]
fn standard_coordinates_flag_round_trips_and_is_refused_on_the_sphere() {
    let sphere = random_sphere(3, 2);
    let mut b = vec![0u8; blob_len(sphere.def())];
    sphere.write_blob(Precision::F32, &mut b).unwrap();
    b[28] |= 4;
    reseal(&mut b);
    assert!(matches!(
        Model4x32::from_blob(&b),
        Err(BlobError::BadHeader(_))
    ));
    // Bit 2 alone, and with bit 3 (the warp).
    for (m, flags) in [
        (random_standardized_half_vector(4, 2), 4),
        (random_warped_half_vector(4, 2), 12),
    ] {
        let bytes = blob_of(&m, Precision::F32);
        assert_eq!(bytes[28] & 12, flags);
        let back = Model3x32::from_blob(&bytes).unwrap();
        assert_eq!(back.def(), m.def());
        assert_eq!(params_of(&back), params_of(&m));
    }
}

/// A model with a latent table on `grid` (docs/math.md, §6.5): the warped half-vector
/// model with node values from a smooth positive function.
fn random_table_model(seed: u64, grid: TableGrid) -> Model3x32 {
    let m = random_warped_half_vector(seed, 2);
    let mut params = params_of(&m);
    let def = diffbsdf::ModelDef {
        latent_table: Some(grid),
        ..*m.def()
    };
    for i in 0..def.table_len() {
        params.push(0.1 + 0.05 * (i % 37) as f32);
    }
    Model3x32::from_params(def, &params).unwrap()
}

/// The table of blob-precision values (flag bit 4 alone, the blobs written before the
/// coded table): its flag and node values survive a write / read round trip in both
/// precisions; without standard coordinates the flag is a header error, and a node value
/// that is not positive, or above `LATENT_TABLE_VALUE_MAX`, a `TableValueOutOfRange` at its
/// index, from a blob as from a parameter vector.
#[test]
fn latent_table_round_trips_and_out_of_range_values_are_refused() {
    let m = random_table_model(6, TableGrid::Values);
    let first_table = m.def().param_count() - m.def().table_len();
    assert_eq!(m.def().table_len(), 32 * 17 * 17);
    for precision in [Precision::F32, Precision::F16] {
        let bytes = blob_of(&m, precision);
        assert_eq!(bytes[28] & 48, 16);
        let back = Model3x32::from_blob(&bytes).unwrap();
        assert_eq!(back.def().latent_table, Some(TableGrid::Values));
        let (a, b) = (params_of(&m), params_of(&back));
        // Node values in [0.1, 1.9]: f16 keeps them to 2^-11 relative.
        assert!(a[first_table..]
            .iter()
            .zip(&b[first_table..])
            .all(|(x, y)| (x - y).abs() <= 1e-3 * x));
    }
    let mut bytes = blob_of(&m, Precision::F32);
    bytes[28] &= !12;
    reseal(&mut bytes);
    assert!(matches!(
        Model3x32::from_blob(&bytes),
        Err(BlobError::BadHeader(_))
    ));
    for bad in [0.0f32, -1.0, 2e6] {
        let index = first_table + 100;
        let mut b = blob_of(&m, Precision::F32);
        let at = HEADER_LEN + 4 * index;
        b[at..at + 4].copy_from_slice(&bad.to_le_bytes());
        reseal(&mut b);
        assert_eq!(
            Model3x32::from_blob(&b).unwrap_err(),
            BlobError::TableValueOutOfRange { index },
            "value {bad}"
        );
        let mut p = params_of(&m);
        p[index] = bad;
        assert_eq!(
            Model3x32::from_params(*m.def(), &p).unwrap_err(),
            BlobError::TableValueOutOfRange { index }
        );
    }
}

/// The coded table (flag bits 4 and 5): one byte per node after the nets' weights in
/// either precision, a read / write round trip bit-exact, its values the codes' (f16-rounded
/// in an f16 blob); a value between two codes is stored as the nearer, one outside the
/// codes' range and code 0 are a `TableValueOutOfRange` at their index, bit 5 without bit 4
/// a header error.
#[test]
fn coded_table_round_trips_and_refuses_what_no_code_holds() {
    let m = random_table_model(7, TableGrid::Codes);
    let def = *m.def();
    let first_table = def.param_count() - def.table_len();
    assert_eq!(def.table_len(), 32 * 33 * 33);
    for precision in [Precision::F32, Precision::F16] {
        let bytes = blob_of(&m, precision);
        assert_eq!(bytes[28] & 48, 48);
        let len = HEADER_LEN + first_table * precision.bytes() + def.table_len() + CHECKSUM_LEN;
        assert_eq!(bytes.len(), len, "{precision:?}");
        let back = Model3x32::from_blob(&bytes).unwrap();
        assert_eq!(back.def().latent_table, Some(TableGrid::Codes));
        assert_eq!(blob_of(&back, precision), bytes, "{precision:?} round trip");
        let (a, b) = (params_of(&m), params_of(&back));
        for (x, y) in a[first_table..].iter().zip(&b[first_table..]) {
            match precision {
                Precision::F32 => assert_eq!(x, y),
                Precision::F16 => assert!((x - y).abs() <= 1e-3 * x, "{x} vs {y}"),
            }
        }
    }
    // Stored as the nearer code: 1.02 is 0.46 of a code step above 1, 1.03 0.68.
    let mut p = params_of(&m);
    p[first_table] = 1.02;
    p[first_table + 1] = 1.03;
    let snapped = params_of(&Model3x32::from_params(def, &p).unwrap());
    assert_eq!(snapped[first_table], 1.0);
    assert_eq!(snapped[first_table + 1], 1.044_273_7);
    let index = first_table + 300;
    for bad in [0.0f32, -1.0, 1e-3, 3000.0, f32::NAN] {
        let mut p = params_of(&m);
        p[index] = bad;
        let want = if bad.is_nan() {
            BlobError::NonFiniteWeight { index }
        } else {
            BlobError::TableValueOutOfRange { index }
        };
        assert_eq!(Model3x32::from_params(def, &p).unwrap_err(), want, "{bad}");
    }
    let mut b = blob_of(&m, Precision::F32);
    b[HEADER_LEN + 4 * first_table + 300] = 0;
    reseal(&mut b);
    assert_eq!(
        Model3x32::from_blob(&b).unwrap_err(),
        BlobError::TableValueOutOfRange { index }
    );
    let mut b = blob_of(&m, Precision::F32);
    b[28] &= !16;
    reseal(&mut b);
    assert!(matches!(
        Model3x32::from_blob(&b),
        Err(BlobError::BadHeader(_))
    ));
}

/// The coded table with its axis warps (flag bits 4, 5 and 6, docs/math.md, (81)): `2 x
/// 33` more codes after the slices', a round trip bit-exact in either precision, an axis
/// node outside the codes' range a `TableValueOutOfRange` at its index, bit 6 without bit
/// 5 a header error.
/// A random model with a coded table on `grid`: `table_len` codes, the header's flag bits
/// 4 and up as `flags` (the byte's high nibble), a round trip bit-exact in either precision.
fn coded_table_round_trips(seed: u64, grid: TableGrid, table_len: usize, flags: u8) -> Model3x32 {
    let m = random_table_model(seed, grid);
    let def = *m.def();
    let first_table = def.param_count() - def.table_len();
    assert_eq!(def.table_len(), table_len);
    for precision in [Precision::F32, Precision::F16] {
        let bytes = blob_of(&m, precision);
        assert_eq!(bytes[28] & 0xf0, flags);
        let len = HEADER_LEN + first_table * precision.bytes() + def.table_len() + CHECKSUM_LEN;
        assert_eq!(bytes.len(), len, "{precision:?}");
        let back = Model3x32::from_blob(&bytes).unwrap();
        assert_eq!(back.def().latent_table, Some(grid));
        assert_eq!(blob_of(&back, precision), bytes, "{precision:?} round trip");
    }
    m
}

#[test]
fn warped_table_round_trips_and_refuses_bad_axis_nodes() {
    let m = coded_table_round_trips(8, TableGrid::WarpedCodes, 32 * 33 * 33 + 2 * 33, 112);
    let def = *m.def();
    let index = def.param_count() - 5;
    let mut p = params_of(&m);
    p[index] = 1e-3;
    assert_eq!(
        Model3x32::from_params(def, &p).unwrap_err(),
        BlobError::TableValueOutOfRange { index }
    );
    let mut b = blob_of(&m, Precision::F32);
    b[28] &= !32;
    reseal(&mut b);
    assert!(matches!(
        Model3x32::from_blob(&b),
        Err(BlobError::BadHeader(_))
    ));
}

/// The warped coded table on the blended layout's 40 slices (flag bits 4 to 7,
/// docs/math.md, (82)): `40 x 33 x 33 + 2 x 33` codes, a round trip bit-exact in either
/// precision; bit 7 without bit 6 a header error, and bit 7 cleared on such a blob leaves a
/// parameter count the 32 slices do not fill, refused too.
#[test]
fn blended_slices_round_trip_and_need_warped_axes() {
    let m = coded_table_round_trips(12, TableGrid::BlendedSlices, 40 * 33 * 33 + 2 * 33, 240);
    let mut b = blob_of(&m, Precision::F32);
    b[28] &= !64;
    reseal(&mut b);
    assert!(matches!(
        Model3x32::from_blob(&b),
        Err(BlobError::BadHeader(_))
    ));
    let mut b = blob_of(&m, Precision::F32);
    b[28] &= !128;
    reseal(&mut b);
    assert!(Model3x32::from_blob(&b).is_err());
}

#[test]
fn non_finite_weights_are_rejected_even_with_a_valid_checksum() {
    let mut b = blob_of(&random_disk(10, 2), Precision::F32);
    b[HEADER_LEN + 4 * 17..HEADER_LEN + 4 * 18].copy_from_slice(&f32::NAN.to_le_bytes());
    reseal(&mut b);
    assert_eq!(
        Model3x32::from_blob(&b).unwrap_err(),
        BlobError::NonFiniteWeight { index: 17 }
    );
    let mut h = blob_of(&random_disk(10, 2), Precision::F16);
    h[HEADER_LEN + 2 * 5..HEADER_LEN + 2 * 6]
        .copy_from_slice(&half::f16::INFINITY.to_bits().to_le_bytes());
    reseal(&mut h);
    assert_eq!(
        Model3x32::from_blob(&h).unwrap_err(),
        BlobError::NonFiniteWeight { index: 5 }
    );
}

#[test]
fn a_blob_of_another_shape_is_a_shape_mismatch_and_load_into_keeps_the_model() {
    let sphere = random_sphere(11, 2);
    let mut def = *sphere.def();
    def.precision = Precision::F32;
    let mut bytes = vec![0u8; blob_len(&def)];
    sphere.write_blob(Precision::F32, &mut bytes).unwrap();
    assert!(Blob::parse(&bytes).is_ok());
    assert_eq!(
        Model3x32::from_blob(&bytes).unwrap_err(),
        BlobError::ShapeMismatch
    );
    assert!(Model4x32::from_blob(&bytes).is_ok());
    let mut disk = random_disk(12, 2);
    let before = disk;
    assert_eq!(
        disk.load_into(&bytes).unwrap_err(),
        BlobError::ShapeMismatch
    );
    assert_eq!(disk, before);
    let mut corrupt = blob_of(&random_disk(13, 2), Precision::F32);
    corrupt[100] ^= 1;
    assert!(disk.load_into(&corrupt).is_err());
    assert_eq!(disk, before);
}

#[test]
fn writer_rejects_bad_input() {
    let m = random_disk(14, 2);
    let def = *m.def();
    let params = params_of(&m);
    let mut small = vec![0u8; 10];
    assert!(matches!(
        write_blob(&def, &params, &mut small),
        Err(BlobError::BufferTooSmall { .. })
    ));
    let mut out = vec![0u8; blob_len(&def)];
    assert!(matches!(
        write_blob(&def, &params[1..], &mut out),
        Err(BlobError::ParamCountMismatch { .. })
    ));
    let mut bad = params.clone();
    bad[3] = f32::INFINITY;
    assert_eq!(
        write_blob(&def, &bad, &mut out),
        Err(BlobError::NonFiniteWeight { index: 3 })
    );
    let mut big = params;
    big[4] = 1e6;
    let mut d16 = def;
    d16.precision = Precision::F16;
    let mut out16 = vec![0u8; blob_len(&d16)];
    assert_eq!(
        write_blob(&d16, &big, &mut out16),
        Err(BlobError::NonFiniteWeight { index: 4 })
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..4096)) {
        prop_assert!(Model3x32::from_blob(&bytes).is_err());
        prop_assert!(Model4x32::from_blob(&bytes).is_err());
    }

    #[test]
    fn random_bytes_after_a_valid_header_never_panic(
        tail in proptest::collection::vec(any::<u8>(), 0..8192), cut in 0usize..64,
    ) {
        let good = blob_of(&random_disk(15, 2), Precision::F16);
        let mut b = good[..HEADER_LEN - cut].to_vec();
        b.extend_from_slice(&tail);
        prop_assert!(Model3x32::from_blob(&b).is_err());
    }
}
