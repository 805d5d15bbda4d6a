/* What trace_saved.c and trace_mpi.c share: opening a saved file, the
 * camera they frame its scene with, and how a hit becomes a pixel, so
 * that a band cast in one process and the whole image cast in another
 * give the same bytes. */
#ifndef SAVED_VIEW_H
#define SAVED_VIEW_H

#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <coray.h>

/* Maps `path` read-only and opens it with coray_saved_open, which checks
 * the file (magic, version, byte order, length, a checksum over every
 * byte), points the scene into it and opens and validates the tree.
 * Every process mapping the file shares one copy in the page cache. 0 on
 * success; the mapping stays for the process's life. */
static int open_saved(const char *path, CoraySaved *saved) {
    int fd = open(path, O_RDONLY);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || st.st_size <= 0) {
        fprintf(stderr, "%s: cannot read\n", path);
        return 1;
    }
    const void *base = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_SHARED, fd, 0);
    close(fd);
    if (base == MAP_FAILED) return 1;
    *saved = coray_saved_default();
    CorayStatus s = coray_saved_open(base, (size_t)st.st_size, saved);
    if (s != CORAY_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", path, coray_status_str(s));
        return 1;
    }
    return 0;
}

/* A size x size camera: the view the file was saved with (`coray build`
 * saves the scene's own; since 1.8), else one on the diagonal of the
 * tree's box, looking at its centre. */
static CorayCamera saved_camera(const CoraySaved *saved, const CorayKdTreeInfo *info, int size) {
    if (saved->has_camera) {
        CorayCamera cam = saved->camera;
        cam.width = cam.height = (uint32_t)size;
        return cam;
    }
    float c[3], ext = 0;
    for (int k = 0; k < 3; k++) {
        c[k] = 0.5f * (info->bounds_min[k] + info->bounds_max[k]);
        ext = fmaxf(ext, info->bounds_max[k] - info->bounds_min[k]);
    }
    CorayCamera cam = coray_camera_default();
    for (int k = 0; k < 3; k++) {
        cam.from[k] = c[k] + (k == 1 ? 0.8f : 1.2f) * ext;
        cam.at[k] = c[k];
    }
    cam.up[1] = 1;
    cam.angle_deg = 45;
    cam.width = cam.height = (uint32_t)size;
    return cam;
}

/* A hit's pixel: grey by how much the normal faces up, blue-ish. */
static void shade(const CorayHit *h, unsigned char px[3]) {
    unsigned char v = 20;
    if (h->geom_id != CORAY_INVALID_ID) {
        float n = sqrtf(h->ng[0] * h->ng[0] + h->ng[1] * h->ng[1] + h->ng[2] * h->ng[2]);
        v = (unsigned char)(40 + 200 * fabsf(h->ng[1]) / n);
    }
    px[0] = px[1] = v;
    px[2] = (unsigned char)(v / 2 + 100);
}

#endif
