/* Conformance harness for the diffbsdf C API, driven by ffi/tests/c_api.rs.
 *
 * usage: harness BLOB SAMPLES PDFS STEPS OUT
 *   SAMPLES: n records of 5 floats (wi[3], u[2]); PDFS: m records of 6 floats (wi, wo).
 *   OUT: per sample record 16 floats (status and wo of sample_direction, status, wo and
 *   pdf of sample, wo of sample_direction_batch, wo and pdf of sample_batch); then per
 *   PDF record 2 floats (pdf, pdf_batch).
 * Also checks the error paths that need a C caller (null, misaligned, short buffers). */
#include "diffbsdf.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK(cond)                                                        \
    do {                                                                   \
        if (!(cond)) {                                                     \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            exit(2);                                                       \
        }                                                                  \
    } while (0)

static void *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    long n;
    void *buf;
    CHECK(f != NULL);
    CHECK(fseek(f, 0, SEEK_END) == 0);
    n = ftell(f);
    CHECK(n >= 0);
    CHECK(fseek(f, 0, SEEK_SET) == 0);
    buf = malloc((size_t)n + 1);
    CHECK(buf != NULL);
    CHECK(fread(buf, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return buf;
}

static void error_paths(const uint8_t *blob, size_t blob_len, const diffbsdf_model *model) {
    float wi[4] = {0.0f, 0.0f, 1.0f, 0.0f}, u[2] = {0.5f, 0.5f}, wo[3], pdf;
    diffbsdf_sample_result s;
    int32_t status = 0;
    uint8_t *bad = (uint8_t *)malloc(blob_len);
    CHECK(bad != NULL);
    CHECK(diffbsdf_sample_direction(NULL, wi, u, 0, wo) == DIFFBSDF_ERR_NULL);
    CHECK(diffbsdf_sample_direction(model, NULL, u, 0, wo) == DIFFBSDF_ERR_NULL);
    CHECK(diffbsdf_sample(model, wi, u, 0, NULL) == DIFFBSDF_ERR_NULL);
    CHECK(diffbsdf_pdf(model, wi, wi, 0, NULL) == DIFFBSDF_ERR_NULL);
    /* A float pointer off by one byte. */
    CHECK(diffbsdf_pdf(model, (const float *)((const char *)wi + 1), wi, 0, &pdf) ==
          DIFFBSDF_ERR_MISALIGNED);
    CHECK(diffbsdf_sample_batch(model, wi, u, (size_t)-1, 0, &s) == DIFFBSDF_ERR_LENGTH);
    CHECK(diffbsdf_model_new(NULL, 10, &status) == NULL && status == DIFFBSDF_ERR_NULL);
    CHECK(diffbsdf_model_new(blob, blob_len - 1, &status) == NULL &&
          status == DIFFBSDF_ERR_TRUNCATED);
    memcpy(bad, blob, blob_len);
    bad[0] = 'X';
    CHECK(diffbsdf_model_new(bad, blob_len, &status) == NULL && status == DIFFBSDF_ERR_BAD_MAGIC);
    memcpy(bad, blob, blob_len);
    bad[blob_len - 1] ^= 0x5a;
    CHECK(diffbsdf_model_new(bad, blob_len, &status) == NULL && status == DIFFBSDF_ERR_CHECKSUM);
    CHECK(diffbsdf_model_init((diffbsdf_model *)bad, 4, blob, blob_len) == DIFFBSDF_ERR_LENGTH);
    CHECK(strlen(diffbsdf_status_message(DIFFBSDF_ERR_CHECKSUM)) > 0);
    CHECK(strcmp(diffbsdf_status_message(12345), "unknown status code") == 0);
    free(bad);
}

int main(int argc, char **argv) {
    size_t blob_len, s_len, p_len, n, m, i;
    uint8_t *blob;
    float *sv, *pv, *out, *bwo, *bpdf;
    diffbsdf_sample_result *bs;
    diffbsdf_model *heap, *mem;
    diffbsdf_info info;
    int32_t status = -100;
    uint32_t steps;
    FILE *f;

    CHECK(argc == 6);
    CHECK(diffbsdf_version() == DIFFBSDF_VERSION);
    CHECK(strcmp(diffbsdf_version_string(), DIFFBSDF_VERSION_STRING) == 0);
    blob = (uint8_t *)read_file(argv[1], &blob_len);
    sv = (float *)read_file(argv[2], &s_len);
    pv = (float *)read_file(argv[3], &p_len);
    steps = (uint32_t)strtoul(argv[4], NULL, 10);
    n = s_len / (5 * sizeof(float));
    m = p_len / (6 * sizeof(float));

    /* Both ways of owning a model; they must answer identically. */
    heap = diffbsdf_model_new(blob, blob_len, &status);
    CHECK(heap != NULL && status == DIFFBSDF_OK);
    CHECK(diffbsdf_model_align() <= 16);
    mem = (diffbsdf_model *)malloc(diffbsdf_model_size());
    CHECK(mem != NULL);
    CHECK(diffbsdf_model_init(mem, diffbsdf_model_size(), blob, blob_len) == DIFFBSDF_OK);
    CHECK(diffbsdf_model_info(mem, &info) == DIFFBSDF_OK);
    CHECK(info.default_steps >= 1 && info.velocity_width == 32);
    error_paths(blob, blob_len, mem);

    out = (float *)calloc(16 * n + 2 * m + 1, sizeof(float));
    bwo = (float *)calloc(3 * n + 1, sizeof(float));
    bs = (diffbsdf_sample_result *)calloc(n + 1, sizeof(diffbsdf_sample_result));
    bpdf = (float *)calloc(m + 1, sizeof(float));
    CHECK(out && bwo && bs && bpdf);
    for (i = 0; i < n; i++) {
        const float *wi = sv + 5 * i, *u = wi + 3;
        float *o = out + 16 * i;
        diffbsdf_sample_result s, s2;
        o[0] = (float)diffbsdf_sample_direction(heap, wi, u, steps, o + 1);
        o[4] = (float)diffbsdf_sample(mem, wi, u, steps, &s);
        CHECK(diffbsdf_sample(heap, wi, u, steps, &s2) == (diffbsdf_status)o[4]);
        CHECK(memcmp(&s, &s2, sizeof s) == 0);
        memcpy(o + 5, s.wo, sizeof s.wo);
        o[8] = s.pdf;
    }
    CHECK(diffbsdf_sample_direction_batch(mem, sv, sv + 3, 0, steps, bwo) == DIFFBSDF_OK);
    /* Inputs are interleaved (stride 5), the batch API is packed: repack. */
    {
        float *wi = (float *)malloc((3 * n + 1) * sizeof(float));
        float *u = (float *)malloc((2 * n + 1) * sizeof(float));
        CHECK(wi && u);
        for (i = 0; i < n; i++) {
            memcpy(wi + 3 * i, sv + 5 * i, 3 * sizeof(float));
            memcpy(u + 2 * i, sv + 5 * i + 3, 2 * sizeof(float));
        }
        CHECK(diffbsdf_sample_direction_batch(mem, wi, u, n, steps, bwo) == DIFFBSDF_OK);
        CHECK(diffbsdf_sample_batch(mem, wi, u, n, steps, bs) == DIFFBSDF_OK);
        free(wi);
        free(u);
    }
    for (i = 0; i < n; i++) {
        float *o = out + 16 * i;
        memcpy(o + 9, bwo + 3 * i, 3 * sizeof(float));
        memcpy(o + 12, bs[i].wo, 3 * sizeof(float));
        o[15] = bs[i].pdf;
    }
    {
        float *wi = (float *)malloc((3 * m + 1) * sizeof(float));
        float *wo = (float *)malloc((3 * m + 1) * sizeof(float));
        CHECK(wi && wo);
        for (i = 0; i < m; i++) {
            memcpy(wi + 3 * i, pv + 6 * i, 3 * sizeof(float));
            memcpy(wo + 3 * i, pv + 6 * i + 3, 3 * sizeof(float));
            CHECK(diffbsdf_pdf(heap, wi + 3 * i, wo + 3 * i, steps, out + 16 * n + 2 * i) ==
                  DIFFBSDF_OK);
        }
        CHECK(diffbsdf_pdf_batch(mem, wi, wo, m, steps, bpdf) == DIFFBSDF_OK);
        for (i = 0; i < m; i++) {
            out[16 * n + 2 * i + 1] = bpdf[i];
        }
        free(wi);
        free(wo);
    }
    f = fopen(argv[5], "wb");
    CHECK(f != NULL);
    CHECK(fwrite(out, sizeof(float), 16 * n + 2 * m, f) == 16 * n + 2 * m);
    fclose(f);
    diffbsdf_model_free(heap);
    diffbsdf_model_free(NULL);
    free(mem);
    free(out);
    free(bwo);
    free(bs);
    free(bpdf);
    free(blob);
    free(sv);
    free(pv);
    printf("ok %lu samples %lu pdfs\n", (unsigned long)n, (unsigned long)m);
    return 0;
}
