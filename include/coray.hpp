/* coray.hpp: a header-only C++17 layer over coray.h.
 *
 * What it adds to the C API, and nothing else: memory the objects own
 * (16-byte aligned, freed by their destructors), errors as exceptions
 * carrying the status, a scene helper (vertices and indices, quads split,
 * spheres),
 * and the build -> shrink -> open steps of a structure in one call. Every
 * call goes to the C function of the same name; the C API's rules
 * (docs/c-api.md) hold unchanged.
 *
 * Ownership: a structure (`coray::Wide`, `coray::KdTree`) owns its scene,
 * its arena and its handle, each on the heap, so moving the structure
 * moves none of what the C handle points at. A `coray::Tracer` records the
 * addresses of itself, its stack and the structure's handle: it can be
 * neither copied nor moved (make it where it stays, one per thread), and
 * the structure must outlive it.
 */
#ifndef CORAY_HPP
#define CORAY_HPP

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "coray.h"

namespace coray {

/// A call that did not return `CORAY_STATUS_OK`: the call's name and the
/// status, with `coray_status_str`'s words as `what()`.
class Error : public std::runtime_error {
 public:
  Error(CorayStatus status, const char *call)
      : std::runtime_error(std::string(call) + ": " + coray_status_str(status)), status_(status) {}
  /// The status the call returned.
  CorayStatus status() const noexcept { return status_; }

 private:
  CorayStatus status_;
};

/// Throws `Error` unless `status` is `CORAY_STATUS_OK`.
inline void check(CorayStatus status, const char *call) {
  if (status != CORAY_STATUS_OK) throw Error(status, call);
}

/// `bytes` of memory aligned to `CORAY_ARENA_ALIGN`, owned; moved, never
/// copied. Arenas, scratch and stacks are all of this kind.
class Arena {
 public:
  Arena() = default;
  explicit Arena(std::size_t bytes) : bytes_(bytes) {
    // aligned_alloc wants a multiple of the alignment.
    std::size_t rounded = (bytes + CORAY_ARENA_ALIGN - 1) / CORAY_ARENA_ALIGN * CORAY_ARENA_ALIGN;
    data_.reset(static_cast<unsigned char *>(std::aligned_alloc(CORAY_ARENA_ALIGN, rounded ? rounded : CORAY_ARENA_ALIGN)));
    if (!data_) throw std::bad_alloc();
  }
  void *data() noexcept { return data_.get(); }
  const void *data() const noexcept { return data_.get(); }
  std::size_t size() const noexcept { return bytes_; }

  /// A new arena of exactly `bytes` holding this one's first `bytes`.
  Arena prefix(std::size_t bytes) const {
    Arena a(bytes);
    if (bytes) std::memcpy(a.data(), data(), bytes);
    return a;
  }

 private:
  struct Free {
    void operator()(unsigned char *p) const noexcept { std::free(p); }
  };
  std::unique_ptr<unsigned char, Free> data_;
  std::size_t bytes_ = 0;
};

/// A scene's arrays, owned: a triangle mesh and spheres. Quads enter as
/// two triangles, (a, b, c) and (a, c, d), under the same watertight test.
struct Scene {
  /// x y z per vertex.
  std::vector<float> vertices;
  /// Three vertex indices per triangle.
  std::vector<std::uint32_t> indices;
  /// x y z radius per sphere.
  std::vector<float> spheres;

  /// Adds a vertex; its index.
  std::uint32_t add_vertex(float x, float y, float z) {
    vertices.insert(vertices.end(), {x, y, z});
    return static_cast<std::uint32_t>(vertices.size() / 3 - 1);
  }
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) { indices.insert(indices.end(), {a, b, c}); }
  void add_quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    add_triangle(a, b, c);
    add_triangle(a, c, d);
  }
  void add_sphere(float x, float y, float z, float radius) { spheres.insert(spheres.end(), {x, y, z, radius}); }
  std::size_t vertex_count() const noexcept { return vertices.size() / 3; }
  std::size_t triangle_count() const noexcept { return indices.size() / 3; }
  std::size_t sphere_count() const noexcept { return spheres.size() / 4; }
  /// Primitives of every kind (triangles first, then spheres: the global
  /// index structures count by).
  std::size_t prim_count() const noexcept { return triangle_count() + sphere_count(); }

  /// The C scene over these arrays (valid while they are not changed).
  CorayScene c_scene() const noexcept {
    CorayScene s = coray_scene_default();
    s.vertices = vertices.data();
    s.vertex_count = vertex_count();
    s.indices = indices.data();
    s.triangle_count = triangle_count();
    s.spheres = spheres.data();
    s.sphere_count = sphere_count();
    return s;
  }
};

class Tracer;

namespace detail {
/// What a built structure owns: its scene, the C scene over it, the
/// arena shrunk to what the tree keeps, and the handle, on the heap.
template <typename Handle>
struct Built {
  Scene scene;
  CorayScene c_scene;
  Arena arena;
  Handle handle;
};

/// One family's C calls that build and open a structure
/// (`coray_<family>_requirements`, `_build`, `_open`, `_info`), and the
/// family's name for errors.
template <typename Handle, typename Params, typename Info>
struct Calls {
  const char *family;
  CorayStatus (*requirements)(std::size_t, const Params *, CorayRequirements *);
  CorayStatus (*build)(const CorayScene *, const Params *, void *, std::size_t, void *, std::size_t, std::size_t *);
  CorayStatus (*open)(const void *, std::size_t, const CorayScene *, Handle *);
  CorayStatus (*info)(const Handle *, Info *);
  Info (*info_default)();

  void check(CorayStatus status, const char *verb) const {
    if (status != CORAY_STATUS_OK) throw Error(status, (std::string("coray_") + family + "_" + verb).c_str());
  }
};

/// Builds over `scene` (moved in) with `params`, shrinks the arena to what
/// the structure keeps (its info's `arena_bytes_used`) and opens it there.
template <typename Handle, typename Params, typename Info>
std::unique_ptr<Built<Handle>> build(const Calls<Handle, Params, Info> &c, Scene scene, const Params &params) {
  auto b = std::make_unique<Built<Handle>>();
  b->scene = std::move(scene);
  b->c_scene = b->scene.c_scene();
  CorayRequirements req = coray_requirements_default();
  c.check(c.requirements(b->scene.prim_count(), &params, &req), "requirements");
  Arena arena(req.arena_bytes), scratch(req.scratch_bytes);
  c.check(c.build(&b->c_scene, &params, arena.data(), arena.size(), scratch.data(), scratch.size(), nullptr), "build");
  Handle full;
  c.check(c.open(arena.data(), arena.size(), &b->c_scene, &full), "open");
  Info info = c.info_default();
  c.check(c.info(&full, &info), "info");
  b->arena = arena.prefix(info.arena_bytes_used);
  c.check(c.open(b->arena.data(), b->arena.size(), &b->c_scene, &b->handle), "open");
  return b;
}

inline const Calls<CorayWide, CorayWideParams, CorayWideInfo> &wide_calls() {
  static const Calls<CorayWide, CorayWideParams, CorayWideInfo> c{
      "wide", coray_wide_requirements, coray_wide_build, coray_wide_open, coray_wide_info, coray_wide_info_default};
  return c;
}

inline const Calls<CorayKdTree, CorayKdParams, CorayKdTreeInfo> &kdtree_calls() {
  static const Calls<CorayKdTree, CorayKdParams, CorayKdTreeInfo> c{"kdtree",
                                                                     coray_kdtree_requirements,
                                                                     coray_kdtree_build,
                                                                     coray_kdtree_open,
                                                                     coray_kdtree_info,
                                                                     coray_kdtree_info_default};
  return c;
}
}  // namespace detail

/// The wide hierarchy over a scene: the structure for triangle meshes and
/// incoherent rays (`coray_wide_*`).
class Wide {
 public:
  /// Builds over `scene` (moved in), shrinks the arena to what the tree
  /// keeps (`arena_bytes_used`) and opens it.
  static Wide build(Scene scene, const CorayWideParams &params = coray_wide_params_default()) {
    return Wide(detail::build(detail::wide_calls(), std::move(scene), params));
  }

  const CorayWide *handle() const noexcept { return &b_->handle; }
  const Scene &scene() const noexcept { return b_->scene; }
  /// The bytes the structure keeps (its arena).
  std::size_t arena_bytes() const noexcept { return b_->arena.size(); }
  CorayWideInfo info() const {
    CorayWideInfo i = coray_wide_info_default();
    check(coray_wide_info(handle(), &i), "coray_wide_info");
    return i;
  }
  /// A traversal stack for one thread's array calls.
  Arena stack() const { return Arena(info().stack_bytes); }

  /// Closest hits of `count` rays (packets of 8 where the CPU has AVX2).
  void intersect(const CorayRay *rays, CorayHit *hits, std::size_t count, Arena &stack) const {
    check(coray_wide_intersect(handle(), rays, hits, count, stack.data(), stack.size(), nullptr), "coray_wide_intersect");
  }
  /// Any-hit queries: `occluded[i]` is 1 when something lies on `rays[i]`.
  void occluded(const CorayRay *rays, std::uint8_t *occluded, std::size_t count, Arena &stack) const {
    check(coray_wide_occluded(handle(), rays, occluded, count, stack.data(), stack.size(), nullptr),
          "coray_wide_occluded");
  }

 private:
  friend class Tracer;
  explicit Wide(std::unique_ptr<detail::Built<CorayWide>> b) : b_(std::move(b)) {}
  std::unique_ptr<detail::Built<CorayWide>> b_;
};

/// An SAH kd-tree over a scene (`coray_kdtree_*`): coherent rays in
/// packets.
class KdTree {
 public:
  /// Builds over `scene` (moved in) with `params`, shrinks the arena to what
  /// the tree keeps (`arena_bytes_used`) and opens it.
  static KdTree build(Scene scene, const CorayKdParams &params = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO)) {
    return KdTree(detail::build(detail::kdtree_calls(), std::move(scene), params));
  }

  const CorayKdTree *handle() const noexcept { return &b_->handle; }
  const Scene &scene() const noexcept { return b_->scene; }
  std::size_t arena_bytes() const noexcept { return b_->arena.size(); }
  CorayKdTreeInfo info() const {
    CorayKdTreeInfo i = coray_kdtree_info_default();
    check(coray_kdtree_info(handle(), &i), "coray_kdtree_info");
    return i;
  }
  /// A traversal stack for one thread's array calls.
  static Arena stack() { return Arena(CORAY_KDTREE_STACK_BYTES); }

  /// Closest hits of `count` rays by `traversal` (`CORAY_TRAVERSAL_PACKETS`
  /// for camera tiles and shadow rays).
  void intersect(CorayTraversal traversal, const CorayRay *rays, CorayHit *hits, std::size_t count,
                 Arena &stack) const {
    check(coray_kdtree_intersect(handle(), traversal, rays, hits, count, stack.data(), stack.size(), nullptr),
          "coray_kdtree_intersect");
  }
  void occluded(CorayTraversal traversal, const CorayRay *rays, std::uint8_t *occluded, std::size_t count,
                Arena &stack) const {
    check(coray_kdtree_occluded(handle(), traversal, rays, occluded, count, stack.data(), stack.size(), nullptr),
          "coray_kdtree_occluded");
  }

 private:
  friend class Tracer;
  explicit KdTree(std::unique_ptr<detail::Built<CorayKdTree>> b) : b_(std::move(b)) {}
  std::unique_ptr<detail::Built<CorayKdTree>> b_;
};

/// One thread's tracer with its own stack: one ray per call, the checks
/// made once. Neither copied nor moved (the C tracer records its own
/// address); the structure it traces must outlive it.
class Tracer {
 public:
  explicit Tracer(const Wide &wide)
      : stack_(wide.info().stack_bytes), intersect1_(coray_wide_tracer_intersect1),
        occluded1_(coray_wide_tracer_occluded1) {
    check(coray_wide_tracer(wide.handle(), stack_.data(), stack_.size(), &t_), "coray_wide_tracer");
  }
  Tracer(const KdTree &tree, CorayTraversal traversal)
      : stack_(CORAY_KDTREE_STACK_BYTES), intersect1_(coray_kdtree_tracer_intersect1),
        occluded1_(coray_kdtree_tracer_occluded1) {
    check(coray_kdtree_tracer(tree.handle(), traversal, stack_.data(), stack_.size(), &t_), "coray_kdtree_tracer");
  }
  Tracer(const Tracer &) = delete;
  Tracer &operator=(const Tracer &) = delete;
  Tracer(Tracer &&) = delete;
  Tracer &operator=(Tracer &&) = delete;

  /// The closest hit of `ray` (a miss: `geom_id` `CORAY_INVALID_ID`).
  CorayHit intersect1(const CorayRay &ray) {
    CorayHit hit;
    check(intersect1_(&t_, &ray, &hit), "tracer_intersect1");
    return hit;
  }
  /// Whether something lies on `ray` within `[tnear, tfar]`.
  bool occluded1(const CorayRay &ray) {
    std::uint8_t o = 0;
    check(occluded1_(&t_, &ray, &o), "tracer_occluded1");
    return o != 0;
  }
  /// Every call's statistics since the tracer was made.
  CorayTraceStats stats() const {
    CorayTraceStats s = coray_trace_stats_default();
    check(coray_tracer_stats(&t_, &s), "coray_tracer_stats");
    return s;
  }

 private:
  Arena stack_;
  // The family's calls, chosen once.
  CorayStatus (*intersect1_)(CorayTracer *, const CorayRay *, CorayHit *);
  CorayStatus (*occluded1_)(CorayTracer *, const CorayRay *, std::uint8_t *);
  CorayTracer t_;
};

}  // namespace coray

#endif /* CORAY_HPP */
