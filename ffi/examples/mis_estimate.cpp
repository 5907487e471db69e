/* Reflected radiance of a rough copper surface under a simple sky, estimated three ways
 * with the diffbsdf C ABI: BSDF sampling with the learned sampler, and MIS (balance
 * heuristic) of the learned sampler with cosine-weighted sampling. Both converge to a
 * deterministic quadrature of the same integral:
 *
 *     L_o(wi) = integral over the hemisphere of f(wi, wo) L(wo) cos(theta_o) dwo
 *
 *   cargo build --release -p diffbsdf-ffi
 *   g++ -std=c++11 -O2 -Wall -Wextra -I ffi/include ffi/examples/mis_estimate.cpp \
 *       target/release/libdiffbsdf_ffi.a -lpthread -ldl -o mis_estimate
 *   ./mis_estimate models/conductor-ggx-a0.3-cu-disk.dbsdf [samples]
 *
 * What a renderer has to get right is marked RENDERER below: the local frame (z = normal,
 * wi and wo point away from the surface), PDFs per unit solid angle, invalid samples
 * counted as zero (never re-drawn: the model's lost mass is not renormalised), and the
 * learned PDF of a direction drawn by another strategy (diffbsdf_pdf) for MIS.
 *
 * Output: one "RESULT" line per incident direction; exit status 0 when every estimate is
 * within 4 standard errors and 3 % of the reference.
 */
#include "diffbsdf.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <random>
#include <vector>

namespace {

const double kPi = 3.14159265358979323846;

struct Vec3 {
    double x, y, z;
};
Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 normalize(Vec3 a) {
    double l = std::sqrt(dot(a, a));
    return {a.x / l, a.y / l, a.z / l};
}

/* The material: GGX rough conductor, alpha 0.3, copper at ~550 nm (one channel). */
const double kAlpha = 0.3;
const std::complex<double> kEta(0.92, 2.45);

double fresnel_conductor(double cos_i) {
    /* Unpolarised Fresnel reflectance of a conductor with complex IOR eta + i k. */
    std::complex<double> c(cos_i, 0.0);
    std::complex<double> sin2 = 1.0 - c * c;
    std::complex<double> cos_t = std::sqrt(1.0 - sin2 / (kEta * kEta));
    std::complex<double> rs = (c - kEta * cos_t) / (c + kEta * cos_t);
    std::complex<double> rp = (kEta * c - cos_t) / (kEta * c + cos_t);
    return 0.5 * (std::norm(rs) + std::norm(rp));
}

double ggx_lambda(Vec3 w) {
    double cos2 = w.z * w.z;
    double tan2 = (1.0 - cos2) / cos2;
    return 0.5 * (-1.0 + std::sqrt(1.0 + kAlpha * kAlpha * tan2));
}

/* f(wi, wo) (no cosine), 0 unless both are above the surface. */
double brdf(Vec3 wi, Vec3 wo) {
    if (wi.z <= 0.0 || wo.z <= 0.0) return 0.0;
    Vec3 h = normalize(wi + wo);
    double a2 = kAlpha * kAlpha;
    double t = h.z * h.z * (a2 - 1.0) + 1.0;
    double d = a2 / (kPi * t * t);
    double g = 1.0 / (1.0 + ggx_lambda(wi) + ggx_lambda(wo));
    return fresnel_conductor(dot(wi, h)) * d * g / (4.0 * wi.z * wo.z);
}

/* The environment: a sky brightening towards the zenith and a soft sun. */
const Vec3 kSun = normalize(Vec3{-0.45, 0.2, 0.85});
double radiance(Vec3 w) {
    if (w.z <= 0.0) return 0.0;
    return 0.3 + 0.7 * w.z + 30.0 * std::exp(40.0 * (dot(w, kSun) - 1.0));
}

/* Deterministic reference: midpoint rule in (cos theta, phi), 512 x 1024 cells. */
double reference(Vec3 wi) {
    const int nm = 512, np = 1024;
    double sum = 0.0;
    for (int i = 0; i < nm; ++i) {
        double mu = (i + 0.5) / nm, s = std::sqrt(1.0 - mu * mu);
        for (int j = 0; j < np; ++j) {
            double phi = 2.0 * kPi * (j + 0.5) / np;
            Vec3 wo{s * std::cos(phi), s * std::sin(phi), mu};
            sum += brdf(wi, wo) * radiance(wo) * mu;
        }
    }
    return sum * (1.0 / nm) * (2.0 * kPi / np);
}

struct Estimate {
    double mean, se;
};
Estimate finish(double s, double s2, long n) {
    double m = s / n, var = (s2 / n - m * m) * n / (n - 1.0);
    return {m, std::sqrt(var / n)};
}

Vec3 to_vec(const float *w) { return {w[0], w[1], w[2]}; }

}  // namespace

int main(int argc, char **argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s MODEL.dbsdf [samples]\n", argv[0]);
        return 2;
    }
    long n = argc > 2 ? std::atol(argv[2]) : 1L << 16;
    std::ifstream file(argv[1], std::ios::binary);
    std::vector<uint8_t> blob((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    int32_t status = 0;
    diffbsdf_model *model = diffbsdf_model_new(blob.data(), blob.size(), &status);
    if (model == NULL) {
        std::fprintf(stderr, "cannot load %s: %s\n", argv[1], diffbsdf_status_message(status));
        return 1;
    }

    std::mt19937 rng(12345);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    int failures = 0;
    const double thetas_deg[] = {0.0, 30.0, 60.0, 80.0};
    for (double theta_deg : thetas_deg) {
        double th = theta_deg * kPi / 180.0;
        Vec3 wi{std::sin(th), 0.0, std::cos(th)};
        float wi_f[3] = {(float)wi.x, (float)wi.y, (float)wi.z};
        double ref = reference(wi);

        double bs = 0, bs2 = 0, ms = 0, ms2 = 0;
        long invalid = 0;
        for (long k = 0; k < n; ++k) {
            /* Strategy 1: the learned sampler. RENDERER: an invalid sample contributes 0. */
            float u[2] = {uni(rng), uni(rng)};
            diffbsdf_sample_result s;
            double est_b = 0.0, mis = 0.0;
            if (diffbsdf_sample(model, wi_f, u, DIFFBSDF_DEFAULT_STEPS, &s) == DIFFBSDF_OK) {
                Vec3 wo = to_vec(s.wo);
                double f = brdf(wi, wo) * radiance(wo) * wo.z;
                est_b = f / s.pdf;
                double p_cos = wo.z > 0 ? wo.z / kPi : 0.0;
                mis += f / (s.pdf + p_cos); /* balance heuristic, one sample per strategy */
            } else {
                ++invalid;
            }
            /* Strategy 2: cosine-weighted hemisphere sampling, with the learned PDF of its
             * direction for the MIS weight. RENDERER: diffbsdf_pdf is the exact density of
             * diffbsdf_sample for that direction (0 where the model cannot sample). */
            double r = std::sqrt((double)uni(rng)), phi = 2.0 * kPi * uni(rng);
            Vec3 wo{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - r * r))};
            float wo_f[3] = {(float)wo.x, (float)wo.y, (float)wo.z};
            float p_learned = 0.0f;
            diffbsdf_pdf(model, wi_f, wo_f, DIFFBSDF_DEFAULT_STEPS, &p_learned);
            double p_cos = wo.z / kPi;
            if (p_cos > 0) mis += brdf(wi, wo) * radiance(wo) * wo.z / (p_learned + p_cos);
            bs += est_b;
            bs2 += est_b * est_b;
            ms += mis;
            ms2 += mis * mis;
        }
        Estimate b = finish(bs, bs2, n), m = finish(ms, ms2, n);
        bool ok_b = std::fabs(b.mean - ref) <= 4.0 * b.se && std::fabs(b.mean - ref) <= 0.03 * ref;
        bool ok_m = std::fabs(m.mean - ref) <= 4.0 * m.se && std::fabs(m.mean - ref) <= 0.03 * ref;
        failures += !ok_b + !ok_m;
        std::printf("RESULT theta_i=%.0f reference=%.6f bsdf=%.6f bsdf_se=%.6f mis=%.6f mis_se=%.6f "
                    "invalid=%.5f %s\n",
                    theta_deg, ref, b.mean, b.se, m.mean, m.se, (double)invalid / n,
                    ok_b && ok_m ? "ok" : "MISMATCH");
    }
    diffbsdf_model_free(model);
    return failures == 0 ? 0 : 1;
}
