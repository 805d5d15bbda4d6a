// include/coray.hpp in use: a cube of quads through the wide hierarchy and
// the kd-tree, tracers, moves, errors. Prints "cpp_wrapper: ok".
#include <cmath>
#include <cstdio>
#include <type_traits>
#include <vector>

#include "coray.hpp"

static_assert(!std::is_copy_constructible_v<coray::Tracer> && !std::is_move_constructible_v<coray::Tracer>,
              "a tracer records its own address");
static_assert(!std::is_copy_constructible_v<coray::Wide> && std::is_nothrow_move_constructible_v<coray::Wide>,
              "a structure moves and is not copied");
static_assert(std::is_nothrow_move_constructible_v<coray::Arena>, "arenas move");

static int failures = 0;
#define EXPECT(c)                                                 \
  do {                                                            \
    if (!(c)) {                                                   \
      std::fprintf(stderr, "%s:%d: %s\n", __FILE__, __LINE__, #c); \
      failures++;                                                 \
    }                                                             \
  } while (0)

/// The cube [-1, 1]^3 as six quads, counter-clockwise seen from outside.
static coray::Scene cube() {
  coray::Scene m;
  for (int i = 0; i < 8; i++) m.add_vertex(i & 1 ? 1.f : -1.f, i & 2 ? 1.f : -1.f, i & 4 ? 1.f : -1.f);
  const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto &f : q) m.add_quad(f[0], f[1], f[2], f[3]);
  return m;
}

/// Rays from outside towards the cube's centre, one per axis and sign,
/// slightly off the diagonals.
static std::vector<CorayRay> rays() {
  std::vector<CorayRay> r;
  for (int axis = 0; axis < 3; axis++)
    for (float sign : {-1.f, 1.f}) {
      CorayRay ray = {{0.1f, 0.2f, 0.3f}, 0.f, {0, 0, 0}, INFINITY};
      ray.org[axis] = 5 * sign;
      ray.dir[axis] = -sign;
      r.push_back(ray);
    }
  return r;
}

int main() {
  coray::Scene m = cube();
  EXPECT(m.triangle_count() == 12 && m.prim_count() == 12);
  coray::Wide wide = coray::Wide::build(cube());
  coray::KdTree kd = coray::KdTree::build(std::move(m));
  EXPECT(wide.arena_bytes() == wide.info().arena_bytes_used);
  EXPECT(kd.arena_bytes() == kd.info().arena_bytes_used);

  // One ray per call: every face at t = 4, the wide hierarchy's hits the
  // kd-tree's bit for bit.
  coray::Tracer tw(wide);
  coray::Tracer tk(kd, CORAY_TRAVERSAL_HIERARCHICAL);
  std::vector<CorayRay> rs = rays();
  for (const CorayRay &r : rs) {
    CorayHit a = tw.intersect1(r), b = tk.intersect1(r);
    EXPECT(a.geom_id == CORAY_GEOM_TRIANGLES && a.t == 4.0f);
    EXPECT(a.prim_id == b.prim_id && a.t == b.t && a.u == b.u && a.v == b.v);
    EXPECT(tw.occluded1(r) && tk.occluded1(r));
    CorayRay away = r;
    for (float &d : away.dir) d = -d;
    EXPECT(tw.intersect1(away).geom_id == CORAY_INVALID_ID && !tw.occluded1(away));
  }
  EXPECT(tw.stats().rays == 4 * rs.size());

  // Array calls, packets on the kd-tree.
  std::vector<CorayHit> hits(rs.size());
  coray::Arena stack = wide.stack();
  wide.intersect(rs.data(), hits.data(), rs.size(), stack);
  for (const CorayHit &h : hits) EXPECT(h.t == 4.0f);
  coray::Arena kstack = coray::KdTree::stack();
  std::vector<std::uint8_t> occ(rs.size());
  kd.occluded(CORAY_TRAVERSAL_PACKETS, rs.data(), occ.data(), rs.size(), kstack);
  for (std::uint8_t o : occ) EXPECT(o == 1);

  // A structure moves with its tracer still valid: nothing the handle
  // points at moved.
  coray::Wide moved = std::move(wide);
  EXPECT(tw.intersect1(rs[0]).t == 4.0f);
  coray::Tracer tm(moved);
  EXPECT(tm.intersect1(rs[1]).t == 4.0f);

  // Errors carry the status.
  coray::Scene bad = cube();
  bad.indices[5] = 100;
  try {
    coray::Wide::build(std::move(bad));
    EXPECT(!"an index out of range was built");
  } catch (const coray::Error &e) {
    EXPECT(e.status() == CORAY_STATUS_INDEX_OUT_OF_RANGE);
    EXPECT(std::string(e.what()).find("coray_wide_build") == 0);
  }
  if (failures) return 1;
  std::printf("cpp_wrapper: ok\n");
  return 0;
}
