/*
 * diffbsdf.h — C API of diffbsdf: importance-sample BSDFs with a tiny learned
 * rectified-flow model.
 *
 * Link with the static library (libdiffbsdf_ffi.a, plus -lm -lpthread -ldl) or the shared
 * library (libdiffbsdf_ffi.so) built by `cargo build --release -p diffbsdf-ffi`.
 *
 * Conventions
 * - Local shading frame: z is the normal; wi points away from the surface.
 * - Directions are float[3], uniform numbers float[2] in [0, 1]; PDFs are per unit solid
 *   angle. A direction is accepted when | |w|^2 - 1 | <= 1e-3 (it is then normalised).
 * - `steps` is the number of Euler steps; 0 (DIFFBSDF_DEFAULT_STEPS) means the model's
 *   default; above DIFFBSDF_MAX_STEPS a call gives no sample (PDF 0). The same convention
 *   holds in Rust and in the generated C, GLSL and WGSL.
 * - Every function returns a diffbsdf_status (or a value that cannot fail). Invalid
 *   numeric input is not an error: sampling answers DIFFBSDF_NO_SAMPLE with zero outputs,
 *   a PDF query answers 0. Null or misaligned pointers (float arrays need 4-byte
 *   alignment) and out-of-range lengths are errors; nothing is written then.
 * - No call allocates except diffbsdf_model_new and the *_parallel batch calls (which
 *   start threads). Calls on one model are thread-safe (the model is read only after
 *   loading).
 */
#ifndef DIFFBSDF_H
#define DIFFBSDF_H

#include <stddef.h>
#include <stdint.h>

#define DIFFBSDF_VERSION_MAJOR 0
#define DIFFBSDF_VERSION_MINOR 1
#define DIFFBSDF_VERSION_PATCH 0
/** major * 10000 + minor * 100 + patch; equals diffbsdf_version() of the library. */
#define DIFFBSDF_VERSION 100
#define DIFFBSDF_VERSION_STRING "0.1.0"

/** Pass as `steps` to use the model's default number of Euler steps. */
#define DIFFBSDF_DEFAULT_STEPS 0u
/** Most Euler steps a call may ask for (bounds the work of one call). */
#define DIFFBSDF_MAX_STEPS 256u

#ifdef __cplusplus
extern "C" {
#endif

/** Status codes: 0 success, 1 no sample (not an error), negative errors. */
typedef enum diffbsdf_status {
    DIFFBSDF_OK = 0,                       /**< Success. */
    DIFFBSDF_NO_SAMPLE = 1,                /**< Invalid input or the sample left the domain; outputs are zero. */
    DIFFBSDF_ERR_NULL = -1,                /**< A required pointer is null. */
    DIFFBSDF_ERR_MISALIGNED = -2,          /**< A pointer is not aligned for its type. */
    DIFFBSDF_ERR_LENGTH = -3,              /**< A length or count is out of range. */
    DIFFBSDF_ERR_PANIC = -4,               /**< Internal error caught at the boundary (a bug). */
    DIFFBSDF_ERR_BAD_MAGIC = -10,          /**< Blob: does not start with "DIFFBSDF". */
    DIFFBSDF_ERR_UNSUPPORTED_VERSION = -11,/**< Blob: format version not supported. */
    DIFFBSDF_ERR_TRUNCATED = -12,          /**< Blob: shorter than its header declares. */
    DIFFBSDF_ERR_TRAILING_BYTES = -13,     /**< Blob: bytes after the checksum. */
    DIFFBSDF_ERR_CHECKSUM = -14,           /**< Blob: CRC-32 mismatch. */
    DIFFBSDF_ERR_UNKNOWN_DOMAIN = -15,     /**< Blob: unknown domain code. */
    DIFFBSDF_ERR_UNKNOWN_PRECISION = -16,  /**< Blob: unknown weight precision code. */
    DIFFBSDF_ERR_UNKNOWN_ACTIVATION = -17, /**< Blob: unknown activation code. */
    DIFFBSDF_ERR_BAD_HEADER = -18,         /**< Blob: a header field is out of range. */
    DIFFBSDF_ERR_PARAM_COUNT = -19,        /**< Blob: parameter count does not match the shape. */
    DIFFBSDF_ERR_NON_FINITE_WEIGHT = -20,  /**< Blob: a weight is NaN or infinite. */
    DIFFBSDF_ERR_SHAPE_MISMATCH = -21,     /**< Blob: an architecture this library is not compiled for. */
    DIFFBSDF_ERR_BUFFER_TOO_SMALL = -22,   /**< An output buffer is too small. */
    DIFFBSDF_ERR_TABLE_VALUE = -23         /**< Blob: a latent-table value or code is out of range. */
} diffbsdf_status;

/** Opaque loaded model. Either allocate diffbsdf_model_size() bytes aligned to
 *  diffbsdf_model_align() and call diffbsdf_model_init, or use diffbsdf_model_new. */
typedef struct diffbsdf_model diffbsdf_model;

/** A sampled direction and its PDF per unit solid angle; all zero when invalid. */
typedef struct diffbsdf_sample_result {
    float wo[3];
    float pdf;
} diffbsdf_sample_result;

/** What a loaded model is. */
typedef struct diffbsdf_info {
    uint32_t domain;                 /**< 0: disk (BRDF, upper hemisphere), 1: sphere (BSDF), 2: equatorial sphere (pole on y), 3: half vector on the disk (BRDF, upper hemisphere). */
    uint32_t precision;              /**< 0: f32 weights in the blob, 1: f16. */
    uint32_t default_steps;          /**< Euler steps used for steps = 0. */
    uint32_t velocity_hidden_layers; /**< 3 or 4. */
    uint32_t velocity_width;         /**< Neurons per hidden layer of the velocity net. */
    uint32_t param_count;            /**< Weights and biases of both nets. */
    uint32_t isotropic;              /**< 1: nets see wi turned to phi = 0 (isotropic BSDF). */
    uint32_t incident_range;         /**< 0: wi.z >= 0 only (other wi: no sample, PDF 0);
                                          1: the whole sphere. */
    uint32_t incident_fold;          /**< The incident azimuths the nets see: 0 all; 1 half the
                                          turn (material unchanged by a half turn about the
                                          normal); 2 a quarter (unchanged by mirroring x and
                                          by mirroring y). Calls fold and unfold by themselves. */
    char name[33];                   /**< The model's name, NUL-terminated. */
} diffbsdf_info;

/** Library version, major * 10000 + minor * 100 + patch. */
uint32_t diffbsdf_version(void);
/** Library version as a static NUL-terminated string, e.g. "0.1.0". */
const char *diffbsdf_version_string(void);
/** Static NUL-terminated description of a status code (also for unknown codes). */
const char *diffbsdf_status_message(int32_t status);

/** Bytes diffbsdf_model_init needs. */
size_t diffbsdf_model_size(void);
/** Alignment diffbsdf_model_init needs. */
size_t diffbsdf_model_align(void);

/** Validates a weight blob and loads it into caller memory `mem` (`mem_len` bytes, at
 *  least diffbsdf_model_size(), aligned to diffbsdf_model_align()). The blob may be freed
 *  afterwards; `mem` needs no cleanup. */
diffbsdf_status diffbsdf_model_init(diffbsdf_model *mem, size_t mem_len,
                                    const uint8_t *blob, size_t blob_len);
/** Validates and loads a blob into a new allocation. Returns null on error, with the
 *  reason in `*status` when `status` is not null. Free with diffbsdf_model_free. */
diffbsdf_model *diffbsdf_model_new(const uint8_t *blob, size_t blob_len, int32_t *status);
/** Frees a model from diffbsdf_model_new; null is ignored. */
void diffbsdf_model_free(diffbsdf_model *model);
/** Describes a loaded model. */
diffbsdf_status diffbsdf_model_info(const diffbsdf_model *model, diffbsdf_info *out);

/** Samples a direction for `wi[3]` and `u[2]` into `wo[3]`, without its PDF (the
 *  cheapest call: no Jacobians). DIFFBSDF_NO_SAMPLE and zeros when invalid. */
diffbsdf_status diffbsdf_sample_direction(const diffbsdf_model *model, const float *wi,
                                          const float *u, uint32_t steps, float *wo);
/** Samples a direction and the PDF it was sampled with. DIFFBSDF_NO_SAMPLE and zeros
 *  when invalid. */
diffbsdf_status diffbsdf_sample(const diffbsdf_model *model, const float *wi,
                                const float *u, uint32_t steps, diffbsdf_sample_result *out);
/** The PDF with which diffbsdf_sample produces `wo[3]` for `wi[3]` (exact inverse of the
 *  sampling map; for MIS). Writes 0 for invalid input. */
diffbsdf_status diffbsdf_pdf(const diffbsdf_model *model, const float *wi, const float *wo,
                             uint32_t steps, float *pdf);

/** Batch diffbsdf_sample_direction: `wi` and `wo` hold 3 * count floats, `u` 2 * count.
 *  Invalid samples are written as zeros. All pointers must be non-null, also for count 0.
 *  Outputs may alias inputs of the same layout. */
diffbsdf_status diffbsdf_sample_direction_batch(const diffbsdf_model *model, const float *wi,
                                                const float *u, size_t count, uint32_t steps,
                                                float *wo);
/** Batch diffbsdf_sample: `out` holds count samples. */
diffbsdf_status diffbsdf_sample_batch(const diffbsdf_model *model, const float *wi,
                                      const float *u, size_t count, uint32_t steps,
                                      diffbsdf_sample_result *out);
/** Batch diffbsdf_pdf: `wi` and `wo` hold 3 * count floats, `pdf` count floats. */
diffbsdf_status diffbsdf_pdf_batch(const diffbsdf_model *model, const float *wi,
                                   const float *wo, size_t count, uint32_t steps, float *pdf);

/** The three batch calls on `threads` threads (0: every core available to the process; at
 *  most 256, and at most one per 256 elements). The batch is cut into contiguous ranges,
 *  one per thread, each computed exactly as the one-thread call computes it: the outputs
 *  do not depend on the thread count. These calls start threads (and so allocate); with
 *  one thread they do not. Same pointer rules as above. */
diffbsdf_status diffbsdf_sample_direction_batch_parallel(const diffbsdf_model *model,
                                                         const float *wi, const float *u,
                                                         size_t count, uint32_t steps,
                                                         uint32_t threads, float *wo);
diffbsdf_status diffbsdf_sample_batch_parallel(const diffbsdf_model *model, const float *wi,
                                               const float *u, size_t count, uint32_t steps,
                                               uint32_t threads, diffbsdf_sample_result *out);
diffbsdf_status diffbsdf_pdf_batch_parallel(const diffbsdf_model *model, const float *wi,
                                            const float *wo, size_t count, uint32_t steps,
                                            uint32_t threads, float *pdf);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* DIFFBSDF_H */
