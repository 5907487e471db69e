/* Loads a diffbsdf weight blob and prints a few samples and their PDFs.
 *
 *   cargo build --release -p diffbsdf-ffi
 *   gcc -std=c99 -Wall -Wextra -pedantic -I ffi/include ffi/examples/sample.c \
 *       target/release/libdiffbsdf_ffi.a -lm -lpthread -ldl -o sample
 *   ./sample models/<model>.dbsdf
 */
#include "diffbsdf.h"

#include <stdio.h>
#include <stdlib.h>

static const char *domain_name(uint32_t domain) {
    switch (domain) {
    case 0: return "BRDF (disk)";
    case 1: return "BSDF (sphere)";
    case 2: return "BSDF (equatorial sphere)";
    case 3: return "BRDF (half vector)";
    default: return "unknown domain";
    }
}

static const char *fold_name(uint32_t fold) {
    switch (fold) {
    case 0: return "every incident azimuth";
    case 1: return "incident azimuths folded by a half turn";
    case 2: return "incident azimuths folded into a quarter turn";
    default: return "unknown fold";
    }
}

int main(int argc, char **argv) {
    FILE *f;
    long len;
    uint8_t *blob;
    int32_t status;
    diffbsdf_model *model;
    diffbsdf_info info;
    float wi[3] = {0.6f, 0.0f, 0.8f};
    int i;

    if (argc != 2) {
        fprintf(stderr, "usage: %s MODEL.dbsdf\n", argv[0]);
        return 2;
    }
    f = fopen(argv[1], "rb");
    if (f == NULL || fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 1;
    }
    blob = (uint8_t *)malloc((size_t)len + 1);
    if (blob == NULL || fread(blob, 1, (size_t)len, f) != (size_t)len) {
        fprintf(stderr, "cannot read %s\n", argv[1]);
        return 1;
    }
    fclose(f);

    model = diffbsdf_model_new(blob, (size_t)len, &status);
    free(blob); /* the model keeps its own copy of the weights */
    if (model == NULL) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], diffbsdf_status_message(status));
        return 1;
    }
    diffbsdf_model_info(model, &info);
    printf("diffbsdf %s, model \"%s\": %s, %s, %u default steps\n", diffbsdf_version_string(), info.name,
           domain_name(info.domain), fold_name(info.incident_fold), info.default_steps);

    for (i = 0; i < 8; i++) {
        /* A stratified u; a renderer would use its sampler here. */
        float u[2] = {((float)i + 0.5f) / 8.0f, 0.37f};
        diffbsdf_sample_result s;
        float pdf = 0.0f;
        if (diffbsdf_sample(model, wi, u, DIFFBSDF_DEFAULT_STEPS, &s) != DIFFBSDF_OK) {
            printf("u = (%.3f, %.3f): no sample\n", u[0], u[1]);
            continue;
        }
        /* The PDF of a given direction (for MIS) agrees with the sampled one. */
        diffbsdf_pdf(model, wi, s.wo, DIFFBSDF_DEFAULT_STEPS, &pdf);
        printf("u = (%.3f, %.3f): wo = (%+.4f, %+.4f, %+.4f), pdf %.5g (pdf(wo) %.5g)\n", u[0], u[1],
               s.wo[0], s.wo[1], s.wo[2], s.pdf, pdf);
    }
    diffbsdf_model_free(model);
    return 0;
}
