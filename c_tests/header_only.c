/* The header alone compiles as strict C99 (and as C++, see c_programs.rs). */
#include "coray.h"

int header_only_probe(void);
int header_only_probe(void) {
    CorayScene s = coray_scene_default();
    CorayKdParams p = coray_kdtree_params_default(CORAY_KD_PRESET_PAPER);
    CorayTraversal t = CORAY_TRAVERSAL_ROPES;
    return (int)s.struct_size + (int)p.leaf_size + (int)CORAY_STATUS_OK + (int)t + CORAY_VERSION_MAJOR;
}
