/* Runs a generated C header (prefix `dbsdf`) on conformance vectors; driven by
 * codegen/tests/c_header.rs.
 *
 * usage: harness SAMPLES PDFS STEPS OUT [PARAMS]
 *   SAMPLES: records of 5 floats (wi, u); PDFS: records of 6 floats (wi, wo);
 *   PARAMS (buffer mode, -DDBSDF_BUFFER): the parameter block, two materials' worth, the
 *   model being the second one (so the base offset is exercised).
 *   OUT: per sample 9 floats (valid, wo of sample_direction; valid, wo, pdf of sample),
 *   then per PDF record 1 float. */
#include GENERATED_HEADER

#include <stdio.h>
#include <stdlib.h>

static float *read_floats(const char *path, size_t *count) {
    FILE *f = fopen(path, "rb");
    long n;
    float *buf;
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(2);
    }
    buf = (float *)malloc((size_t)n + sizeof(float));
    if (buf == NULL || fread(buf, 1, (size_t)n, f) != (size_t)n) {
        fprintf(stderr, "cannot read %s\n", path);
        exit(2);
    }
    fclose(f);
    *count = (size_t)n / sizeof(float);
    return buf;
}

int main(int argc, char **argv) {
    size_t ns, np, i;
    float *sv, *pv, *out;
    unsigned steps;
    FILE *f;
#ifdef DBSDF_BUFFER
    size_t nparams;
    float *all;
    const float *params;
    if (argc != 6) {
        return 2;
    }
    all = read_floats(argv[5], &nparams);
    if (nparams != 2 * DBSDF_PARAM_COUNT) {
        fprintf(stderr, "parameter file has %lu floats\n", (unsigned long)nparams);
        return 2;
    }
    params = all + DBSDF_PARAM_COUNT;
#define ARGS params,
#else
    if (argc != 5) {
        return 2;
    }
#define ARGS
#endif
    sv = read_floats(argv[1], &ns);
    pv = read_floats(argv[2], &np);
    ns /= 5;
    np /= 6;
    steps = (unsigned)strtoul(argv[3], NULL, 10);
    out = (float *)calloc(9 * ns + np + 1, sizeof(float));
    if (out == NULL) {
        return 2;
    }
    for (i = 0; i < ns; i++) {
        const float *wi = sv + 5 * i, *u = wi + 3;
        float *o = out + 9 * i;
        o[0] = (float)(dbsdf_sample_direction(ARGS wi, u, steps, o + 1) == DBSDF_OK);
        o[4] = (float)(dbsdf_sample(ARGS wi, u, steps, o + 5, o + 8) == DBSDF_OK);
    }
    for (i = 0; i < np; i++) {
        out[9 * ns + i] = dbsdf_pdf(ARGS pv + 6 * i, pv + 6 * i + 3, steps);
    }
    f = fopen(argv[4], "wb");
    if (f == NULL || fwrite(out, sizeof(float), 9 * ns + np, f) != 9 * ns + np) {
        return 2;
    }
    fclose(f);
    printf("ok %lu %lu\n", (unsigned long)ns, (unsigned long)np);
    return 0;
}
