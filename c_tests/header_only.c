/* The header alone compiles as strict C99 (and as C++, see c_programs.rs). */
#include "coray.h"

int header_only_probe(void);
int header_only_probe(void) {
    CorayScene s = coray_scene_default();
    CorayKdParams p = coray_kd_params_default(CORAY_KD_PRESET_PAPER);
    return (int)s.struct_size + (int)p.leaf_size + (int)CORAY_STATUS_OK;
}
