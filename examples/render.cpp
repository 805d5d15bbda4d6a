// coray from C++ through coray.hpp: a tree shared by std::threads
// (each with its own traversal stack), primary rays traced as arrays in
// packets of 8 (CORAY_TRAVERSAL_PACKETS). A procedural scene: a floor and a
// grid of balls. Writes a PPM.
//
//   render_cpp OUT.ppm [SIZE] [THREADS]
//
// Build against the installed library:
//   c++ -std=c++17 render.cpp $(pkg-config --cflags --libs coray) -pthread -o render_cpp
#include <coray.hpp>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Vec {
    float x, y, z;
    Vec operator+(Vec o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec operator-(Vec o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec operator*(float s) const { return {x * s, y * s, z * s}; }
    float dot(Vec o) const { return x * o.x + y * o.y + z * o.z; }
    Vec cross(Vec o) const { return {y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x}; }
    Vec unit() const { return *this * (1.0f / std::sqrt(dot(*this))); }
};

} // namespace

int main(int argc, char **argv) try {
    if (argc < 2) {
        std::fprintf(stderr, "usage: render_cpp OUT.ppm [SIZE] [THREADS]\n");
        return 2;
    }
    const int size = argc > 2 ? std::atoi(argv[2]) : 256;
    const int threads = argc > 3 ? std::atoi(argv[3]) : int(std::thread::hardware_concurrency());
    if (size < 8 || size > 8192 || size % 4 != 0 || threads < 1 || threads > 256)
        throw std::runtime_error("SIZE must be a multiple of 4 from 8 to 8192, THREADS 1 to 256");

    // A 20 x 20 floor and a 7 x 7 grid of balls.
    coray::Scene scene;
    scene.add_quad(scene.add_vertex(-10, 0, -10), scene.add_vertex(-10, 0, 10), scene.add_vertex(10, 0, 10),
                   scene.add_vertex(10, 0, -10));
    for (int i = 0; i < 7; i++)
        for (int k = 0; k < 7; k++) scene.add_sphere(float(i - 3) * 2.2f, 1.0f, float(k - 3) * 2.2f, 0.9f);
    const size_t prims = scene.prim_count();
    const coray::KdTree tree = coray::KdTree::build(std::move(scene));

    // A pinhole camera with an orthonormal basis (so balls come out round):
    // rays of 4 x 2 pixel tiles in a row, packets of 8 that move alike.
    const Vec eye{0, 9, 16}, at{0, 0, 0}, light{6, 14, 8};
    const Vec forward = (at - eye).unit(), right = forward.cross(Vec{0, 1, 0}).unit(), up = right.cross(forward);
    const float half = std::tan(0.5f * 50.0f * 3.14159265f / 180.0f); // a 50-degree field of view
    auto camera_ray = [&](int x, int y) {
        const float sx = (2.0f * (x + 0.5f) / size - 1.0f) * half, sy = (1.0f - 2.0f * (y + 0.5f) / size) * half;
        const Vec d = forward + right * sx + up * sy;
        return CorayRay{{eye.x, eye.y, eye.z}, 0.0f, {d.x, d.y, d.z}, INFINITY};
    };
    std::vector<unsigned char> image(size_t(size) * size * 3);
    std::atomic<int> next_band{0};
    auto worker = [&] {
        coray::Arena stack = coray::KdTree::stack(); // one stack per thread
        std::vector<CorayRay> rays(size_t(size) * 2), shadows(rays.size());
        std::vector<CorayHit> hits(rays.size());
        std::vector<uint8_t> blocked(rays.size());
        for (int band; (band = next_band++) < size / 2;) {
            for (int bx = 0; bx < size; bx += 4)
                for (int t = 0; t < 8; t++) rays[size_t(bx) * 2 + t] = camera_ray(bx + t % 4, 2 * band + t / 4);
            tree.intersect(CORAY_TRAVERSAL_PACKETS, rays.data(), hits.data(), rays.size(), stack);
            for (size_t i = 0; i < rays.size(); i++) {
                CorayRay &s = shadows[i];
                s = CorayRay{};
                const float t = hits[i].geom_id == CORAY_INVALID_ID ? 0.0f : hits[i].t;
                for (int k = 0; k < 3; k++) {
                    s.org[k] = rays[i].org[k] + t * rays[i].dir[k];
                    s.dir[k] = (&light.x)[k] - s.org[k];
                }
                s.tnear = 1e-4f;
                s.tfar = hits[i].geom_id == CORAY_INVALID_ID ? -1.0f : 1.0f; // a miss casts no shadow ray
            }
            tree.occluded(CORAY_TRAVERSAL_PACKETS, shadows.data(), blocked.data(), shadows.size(), stack);
            for (size_t i = 0; i < rays.size(); i++) {
                const int x = int(i / 8) * 4 + int(i % 4), y = 2 * band + int(i % 8) / 4;
                const CorayHit &h = hits[i];
                float c = 0.15f;
                if (h.geom_id != CORAY_INVALID_ID) {
                    const float *d = shadows[i].dir;
                    const float n = std::sqrt(h.ng[0] * h.ng[0] + h.ng[1] * h.ng[1] + h.ng[2] * h.ng[2]);
                    const float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                    float lambert = (h.ng[0] * d[0] + h.ng[1] * d[1] + h.ng[2] * d[2]) / (n * l);
                    lambert = std::fabs(lambert);
                    c = blocked[i] ? 0.1f : 0.1f + 0.8f * lambert;
                }
                unsigned char *px = &image[(size_t(y) * size + x) * 3];
                px[0] = px[1] = px[2] = static_cast<unsigned char>(std::pow(std::fmin(c, 1.0f), 1 / 2.2f) * 255);
                if (h.geom_id == CORAY_GEOM_SPHERES) px[0] = static_cast<unsigned char>(px[0] * 0.6f);
            }
        }
    };
    std::vector<std::thread> pool;
    for (int i = 0; i < threads; i++) pool.emplace_back(worker);
    for (auto &t : pool) t.join();

    std::unique_ptr<std::FILE, int (*)(std::FILE *)> out(std::fopen(argv[1], "wb"), std::fclose);
    if (!out) throw std::runtime_error(std::string(argv[1]) + ": cannot write");
    std::fprintf(out.get(), "P6\n%d %d\n255\n", size, size);
    std::fwrite(image.data(), 1, image.size(), out.get());
    std::printf("%zu primitives, %dx%d in packets of 8 on %d threads -> %s\n", prims, size, size, threads, argv[1]);
    return 0;
} catch (const std::exception &e) {
    std::fprintf(stderr, "render_cpp: %s\n", e.what());
    return 1;
}
