// coray from C++: arenas owned by RAII types, a tree shared by std::threads
// (each with its own traversal stack), primary rays traced as arrays in
// packets of 8 (CORAY_TRAVERSAL_PACKETS). A procedural scene: a floor and a
// grid of balls. Writes a PPM.
//
//   render_cpp OUT.ppm [SIZE] [THREADS]
//
// Build against the installed library:
//   c++ -std=c++17 render.cpp $(pkg-config --cflags --libs coray) -pthread -o render_cpp
#include <coray.h>

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

// Throws on any status but OK, with coray's description of it.
void check(CorayStatus s, const char *what) {
    if (s != CORAY_STATUS_OK) throw std::runtime_error(std::string(what) + ": " + coray_status_str(s));
}

// CORAY_ARENA_ALIGN-aligned memory that frees itself.
class Arena {
  public:
    explicit Arena(size_t bytes) : bytes_(bytes) {
        void *p = nullptr;
        if (posix_memalign(&p, CORAY_ARENA_ALIGN, bytes ? bytes : 16) != 0) throw std::bad_alloc();
        p_.reset(p);
    }
    void *data() const { return p_.get(); }
    size_t size() const { return bytes_; }

  private:
    struct Free {
        void operator()(void *p) const { std::free(p); }
    };
    std::unique_ptr<void, Free> p_;
    size_t bytes_;
};

// A built kd-tree over a scene: the arena it lives in and its handle. The
// scene's arrays must outlive it (the tree holds primitive indices).
class KdTree {
  public:
    KdTree(const CorayScene &scene, CorayKdPreset preset) : arena_(size(scene, preset)) {
        CorayKdParams params = coray_kdtree_params_default(preset);
        CorayRequirements req = coray_requirements_default();
        check(coray_kdtree_requirements(count(scene), &params, &req), "requirements");
        Arena scratch(req.scratch_bytes); // free again when the build returns
        check(coray_kdtree_build(&scene, &params, arena_.data(), arena_.size(), scratch.data(), scratch.size(), nullptr),
              "build");
        check(coray_kdtree_open(arena_.data(), arena_.size(), &scene, &handle_), "open");
    }
    const CorayKdTree *handle() const { return &handle_; }

  private:
    static size_t count(const CorayScene &s) { return s.triangle_count + s.sphere_count + s.cone_count; }
    static size_t size(const CorayScene &s, CorayKdPreset preset) {
        CorayKdParams params = coray_kdtree_params_default(preset);
        CorayRequirements req = coray_requirements_default();
        check(coray_kdtree_requirements(count(s), &params, &req), "requirements");
        return req.arena_bytes;
    }
    Arena arena_;
    CorayKdTree handle_{};
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
    std::vector<float> vertices = {-10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10};
    std::vector<uint32_t> indices = {0, 1, 2, 0, 2, 3};
    std::vector<float> spheres;
    for (int i = 0; i < 7; i++)
        for (int k = 0; k < 7; k++) spheres.insert(spheres.end(), {float(i - 3) * 2.2f, 1.0f, float(k - 3) * 2.2f, 0.9f});
    CorayScene scene = coray_scene_default();
    scene.vertices = vertices.data();
    scene.vertex_count = vertices.size() / 3;
    scene.indices = indices.data();
    scene.triangle_count = indices.size() / 3;
    scene.spheres = spheres.data();
    scene.sphere_count = spheres.size() / 4;
    const KdTree tree(scene, CORAY_KD_PRESET_AUTO);

    // Rays of 4 x 2 pixel tiles in a row: packets of 8 that move alike.
    const float eye[3] = {0, 9, 16}, light[3] = {6, 14, 8};
    auto camera_ray = [&](int x, int y) {
        CorayRay r{};
        const float sx = (2.0f * (x + 0.5f) / size - 1.0f) * 0.5f, sy = (1.0f - 2.0f * (y + 0.5f) / size) * 0.5f;
        const float d[3] = {sx, -0.45f + sy * 0.9f, -0.9f + sy * 0.45f};
        for (int k = 0; k < 3; k++) {
            r.org[k] = eye[k];
            r.dir[k] = d[k];
        }
        r.tfar = INFINITY;
        return r;
    };
    std::vector<unsigned char> image(size_t(size) * size * 3);
    std::atomic<int> next_band{0};
    auto worker = [&] {
        Arena stack(CORAY_KDTREE_STACK_BYTES); // one stack per thread
        std::vector<CorayRay> rays(size_t(size) * 2), shadows(rays.size());
        std::vector<CorayHit> hits(rays.size());
        std::vector<uint8_t> blocked(rays.size());
        for (int band; (band = next_band++) < size / 2;) {
            for (int bx = 0; bx < size; bx += 4)
                for (int t = 0; t < 8; t++) rays[size_t(bx) * 2 + t] = camera_ray(bx + t % 4, 2 * band + t / 4);
            check(coray_kdtree_intersect(tree.handle(), CORAY_TRAVERSAL_PACKETS, rays.data(), hits.data(), rays.size(),
                                         stack.data(), stack.size(), nullptr),
                  "intersect");
            for (size_t i = 0; i < rays.size(); i++) {
                CorayRay &s = shadows[i];
                s = CorayRay{};
                const float t = hits[i].geom_id == CORAY_INVALID_ID ? 0.0f : hits[i].t;
                for (int k = 0; k < 3; k++) {
                    s.org[k] = rays[i].org[k] + t * rays[i].dir[k];
                    s.dir[k] = light[k] - s.org[k];
                }
                s.tnear = 1e-4f;
                s.tfar = hits[i].geom_id == CORAY_INVALID_ID ? -1.0f : 1.0f; // a miss casts no shadow ray
            }
            check(coray_kdtree_occluded(tree.handle(), CORAY_TRAVERSAL_PACKETS, shadows.data(), blocked.data(),
                                        shadows.size(), stack.data(), stack.size(), nullptr),
                  "occluded");
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
    std::printf("%zu primitives, %dx%d in packets of 8 on %d threads -> %s\n", spheres.size() / 4 + 2, size, size, threads,
                argv[1]);
    return 0;
} catch (const std::exception &e) {
    std::fprintf(stderr, "render_cpp: %s\n", e.what());
    return 1;
}
