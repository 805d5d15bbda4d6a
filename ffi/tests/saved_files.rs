//! Saved files (`coray build SCENE -o FILE`, format version 2) through
//! `coray_saved_open` (issue 55.2): a sound file opens and traces as a
//! fresh build; any flipped bit, a truncated or extended file, another
//! version or byte order is `CORAY_STATUS_DAMAGED_FILE`; a file forged
//! with a correct checksum over a changed scene is `CORRUPT_ARENA` (the
//! tree's scene digest). Version 1 had no checksum: 5 of 600 bit flips
//! in its scene arrays opened, validated and changed the image.

use coray_ffi::saved::{checksum, kdtree_file};
use coray_ffi::*;
use core::ffi::c_void;

/// 16-byte aligned bytes, as `mmap` and `malloc` give.
struct Aligned(Vec<u128>, usize);

impl Aligned {
    fn of(bytes: &[u8]) -> Aligned {
        let mut v = vec![0u128; bytes.len().div_ceil(16).max(1)];
        for (w, c) in v.iter_mut().zip(bytes.chunks(16)) {
            let mut b = [0u8; 16];
            b[..c.len()].copy_from_slice(c);
            *w = u128::from_ne_bytes(b);
        }
        Aligned(v, bytes.len())
    }
    fn ptr(&self) -> *const c_void {
        self.0.as_ptr().cast()
    }
}

fn open(bytes: &[u8]) -> (CorayStatus, CoraySaved, Aligned) {
    let a = Aligned::of(bytes);
    let mut out = coray_saved_default();
    let s = unsafe { coray_saved_open(a.ptr(), a.1, &mut out) };
    (s, out, a)
}

/// Writes `b`'s checksum again after a change, so that the change and not
/// the checksum is what `coray_saved_open` judges.
fn resum(b: &mut [u8]) {
    let sum = checksum(b);
    b[24..32].copy_from_slice(&sum.to_ne_bytes());
}

/// Every file of `cases` is refused as damaged (the case named on failure).
fn assert_all_damaged(cases: &[(&str, Vec<u8>)]) {
    for (what, b) in cases {
        assert_eq!(open(b).0, CorayStatus::DamagedFile, "{what}");
    }
}

struct Owned {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    spheres: Vec<coray::Sphere>,
    cones: Vec<coray::Cone>,
}

/// A few dozen triangles in a fan, spheres and a cone.
fn owned() -> Owned {
    let mut o = Owned {
        vertices: vec![[0.0, 0.0, 0.0]],
        triangles: Vec::new(),
        spheres: Vec::new(),
        cones: Vec::new(),
    };
    for i in 0..40u32 {
        let a = i as f32 * 0.157;
        o.vertices
            .push([3.0 * a.cos(), 3.0 * a.sin(), 0.2 * i as f32]);
        if i > 0 {
            o.triangles.push([0, i, i + 1]);
        }
    }
    for i in 0..6 {
        o.spheres.push(coray::Sphere {
            center: [i as f32 - 3.0, 1.0, 2.0],
            radius: 0.4,
        });
    }
    o.cones.push(coray::Cone {
        base: [0.0, -2.0, 0.0],
        base_radius: 0.5,
        apex: [0.0, -2.0, 3.0],
        apex_radius: 0.1,
    });
    o
}

impl Owned {
    fn scene(&self) -> coray::Scene<'_> {
        coray::Scene {
            vertices: &self.vertices,
            triangles: &self.triangles,
            spheres: &self.spheres,
            cones: &self.cones,
        }
    }
}

/// Closest hits of a fan of rays down the z axis through the tree of `s`.
fn trace(tree: &CorayKdTree) -> Vec<(u32, u32, u32)> {
    let rays: Vec<CorayRay> = (0..400)
        .map(|i| CorayRay {
            org: [
                (i % 20) as f32 * 0.35 - 3.5,
                (i / 20) as f32 * 0.35 - 3.5,
                20.0,
            ],
            tnear: 0.0,
            dir: [0.0, 0.0, -1.0],
            tfar: f32::INFINITY,
        })
        .collect();
    let mut hits = vec![CorayHit::default(); rays.len()];
    let mut stack = vec![0u128; CORAY_KDTREE_STACK_BYTES / 16];
    let s = unsafe {
        coray_kdtree_intersect(
            tree,
            CORAY_TRAVERSAL_HIERARCHICAL,
            rays.as_ptr(),
            hits.as_mut_ptr(),
            rays.len(),
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            core::ptr::null_mut(),
        )
    };
    assert_eq!(s, CorayStatus::Ok);
    hits.iter()
        .map(|h| (h.geom_id, h.prim_id, h.t.to_bits()))
        .collect()
}

#[test]
fn a_sound_file_opens_and_traces_as_its_scene() {
    let o = owned();
    let bytes = kdtree_file(&o.scene(), None, CORAY_KD_PRESET_AUTO, 0).unwrap();
    let (s, saved, _file) = open(&bytes);
    assert_eq!(s, CorayStatus::Ok);
    assert_eq!(saved.preset, CORAY_KD_PRESET_AUTO);
    assert_eq!(
        (saved.scene.vertex_count, saved.scene.triangle_count),
        (41, 39)
    );
    assert_eq!((saved.scene.sphere_count, saved.scene.cone_count), (6, 1));
    // The same hits as a tree built over the scene in memory.
    let (arena, used) = {
        let b = kdtree_file(&o.scene(), None, CORAY_KD_PRESET_AUTO, 0).unwrap();
        let at = u64::from_ne_bytes(b[96..104].try_into().unwrap()) as usize;
        let n = u64::from_ne_bytes(b[104..112].try_into().unwrap()) as usize;
        (Aligned::of(&b[at..at + n]), n)
    };
    let c = {
        let mut c = coray_scene_default();
        c.vertices = o.vertices.as_ptr().cast();
        c.vertex_count = o.vertices.len();
        c.indices = o.triangles.as_ptr().cast();
        c.triangle_count = o.triangles.len();
        c.spheres = o.spheres.as_ptr().cast();
        c.sphere_count = o.spheres.len();
        c.cones = o.cones.as_ptr().cast();
        c.cone_count = o.cones.len();
        c
    };
    let mut tree = CorayKdTree { opaque: [0; 32] };
    assert_eq!(
        unsafe { coray_kdtree_open(arena.ptr(), used, &c, &mut tree) },
        CorayStatus::Ok
    );
    let want = trace(&tree);
    assert!(want.iter().filter(|h| h.0 != u32::MAX).count() > 100);
    assert_eq!(trace(&saved.tree), want);
}

/// Every bit of a small file flipped, one at a time: each refused as
/// damaged (the checksum's own bits too).
#[test]
fn every_flipped_bit_is_a_damaged_file() {
    let o = owned();
    for omit_ropes in [0, 2] {
        let bytes =
            kdtree_file(&o.scene(), Some(&view()), CORAY_KD_PRESET_PAPER, omit_ropes).unwrap();
        for bit in 0..8 * bytes.len() {
            let mut bad = bytes.clone();
            bad[bit / 8] ^= 1 << (bit % 8);
            let (s, ..) = open(&bad);
            assert_eq!(s, CorayStatus::DamagedFile, "bit {bit} of {}", bytes.len());
        }
    }
}

#[test]
fn truncated_extended_other_versions_and_byte_orders_are_damaged() {
    let o = owned();
    let bytes = kdtree_file(&o.scene(), None, CORAY_KD_PRESET_AUTO, 0).unwrap();
    let mut cases: Vec<(&str, Vec<u8>)> = vec![
        ("empty", Vec::new()),
        ("header only", bytes[..128].to_vec()),
        ("one byte short", bytes[..bytes.len() - 1].to_vec()),
    ];
    let mut longer = bytes.clone();
    longer.extend_from_slice(&[0; 16]);
    cases.push(("16 bytes more", longer));
    for (what, at, value) in [
        ("version 1", 8, 1u32),
        ("version 4", 8, 4),
        ("the other byte order", 12, 0x0403_0201),
    ] {
        let mut b = bytes.clone();
        b[at..at + 4].copy_from_slice(&value.to_ne_bytes());
        resum(&mut b);
        cases.push((what, b));
    }
    // An array placed past the end, or off 16 bytes, checksum made again.
    for (what, word, value) in [
        ("vertices past the end", 8, 1u64 << 40),
        ("triangles misaligned", 9, 136),
        ("too many spheres", 6, 1 << 30),
        ("arena past the end", 13, 1 << 40),
    ] {
        let mut b = bytes.clone();
        b[8 * word..8 * word + 8].copy_from_slice(&value.to_ne_bytes());
        resum(&mut b);
        cases.push((what, b));
    }
    assert_all_damaged(&cases);
    // A sound file: NULL, misaligned, no out struct.
    let a = Aligned::of(&bytes);
    let mut out = coray_saved_default();
    unsafe {
        assert_eq!(
            coray_saved_open(core::ptr::null(), a.1, &mut out),
            CorayStatus::NullPointer
        );
        let off = a.ptr().cast::<u8>().add(4).cast();
        assert_eq!(
            coray_saved_open(off, a.1 - 4, &mut out),
            CorayStatus::Misaligned
        );
        assert_eq!(
            coray_saved_open(a.ptr(), a.1, core::ptr::null_mut()),
            CorayStatus::NullPointer
        );
    }
    assert_eq!(open(&bytes).0, CorayStatus::Ok);
}

/// A file forged with a correct checksum over a changed scene word (a
/// triangle index, a vertex bit): the tree's scene digest refuses it. In
/// version 1 a flipped triangle index validated and cast 164 pixels
/// unlike a fresh build.
#[test]
fn a_forged_file_over_a_changed_scene_is_corrupt() {
    let o = owned();
    let bytes = kdtree_file(&o.scene(), None, CORAY_KD_PRESET_AUTO, 0).unwrap();
    let word = |k: usize| u64::from_ne_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap());
    let (vertices, triangles) = (word(8) as usize, word(9) as usize);
    for at in [triangles + 4 * 7, vertices + 4 * 20, vertices + 4 * 4] {
        let mut bad = bytes.clone();
        bad[at] ^= 1;
        let sum = checksum(&bad);
        bad[24..32].copy_from_slice(&sum.to_ne_bytes());
        assert_eq!(open(&bad).0, CorayStatus::CorruptArena, "byte {at}");
    }
}

/// The camera format 3 saves with the scene (`coray build` writes the
/// scene's own).
fn view() -> coray::Camera {
    coray::Camera {
        from: coray::Vec3::new(1.0, 2.0, 9.0),
        at: coray::Vec3::new(0.0, 0.5, 0.0),
        up: coray::Vec3::Y,
        angle_deg: 40.0,
        width: 320,
        height: 200,
    }
}

/// Format 3 keeps the view: it opens as it was written; a file without
/// one, and a version 2 file (1.7's, no view), open with `has_camera` 0;
/// a view past the end, misaligned, in a version 2 file or no usable
/// camera (a forged file, checksum made again) is damage; a caller built
/// against 1.7 (its struct ending at `tree`) gets no camera written.
#[test]
fn the_view_is_kept_and_checked() {
    let o = owned();
    let with = kdtree_file(&o.scene(), Some(&view()), CORAY_KD_PRESET_AUTO, 0).unwrap();
    let (s, saved, _f) = open(&with);
    assert_eq!(s, CorayStatus::Ok);
    assert_eq!(saved.has_camera, 1);
    let c = saved.camera;
    assert_eq!(c.struct_size, core::mem::size_of::<CorayCamera>());
    assert_eq!(
        (c.from, c.at, c.up),
        ([1.0, 2.0, 9.0], [0.0, 0.5, 0.0], [0.0, 1.0, 0.0])
    );
    assert_eq!((c.angle_deg, c.width, c.height), (40.0, 320, 200));

    let without = kdtree_file(&o.scene(), None, CORAY_KD_PRESET_AUTO, 0).unwrap();
    let (s, saved, _f) = open(&without);
    assert_eq!((s, saved.has_camera), (CorayStatus::Ok, 0));
    let mut v2 = without.clone();
    v2[8..12].copy_from_slice(&2u32.to_ne_bytes());
    resum(&mut v2);
    let (s, saved, _f) = open(&v2);
    assert_eq!((s, saved.has_camera), (CorayStatus::Ok, 0), "a 1.7 file");

    let view_at = u64::from_ne_bytes(with[120..128].try_into().unwrap()) as usize;
    assert!(view_at >= 128 && view_at.is_multiple_of(16));
    let mut cases: Vec<(&str, Vec<u8>)> = Vec::new();
    for (what, at) in [
        ("past the end", with.len() as u64),
        ("misaligned", view_at as u64 + 4),
        ("in the header", 64),
    ] {
        let mut b = with.clone();
        b[120..128].copy_from_slice(&at.to_ne_bytes());
        resum(&mut b);
        cases.push((what, b));
    }
    let mut b = with.clone();
    b[8..12].copy_from_slice(&2u32.to_ne_bytes());
    resum(&mut b);
    cases.push(("a view in a version 2 file", b));
    for (what, k, value) in [
        ("a NaN eye", 0, f32::NAN.to_bits()),
        ("the eye on the point looked at", 3, 1.0f32.to_bits()),
        ("no width", 10, 0),
    ] {
        let mut b = with.clone();
        let at = view_at + 4 * k;
        if k == 3 {
            // at = from: all three coordinates.
            b.copy_within(view_at..view_at + 12, view_at + 12);
        } else {
            b[at..at + 4].copy_from_slice(&value.to_ne_bytes());
        }
        resum(&mut b);
        cases.push((what, b));
    }
    assert_all_damaged(&cases);

    // A 1.7 caller's struct: nothing written past its `tree`.
    let a = Aligned::of(&with);
    let mut out = coray_saved_default();
    let old = core::mem::offset_of!(CoraySaved, camera);
    out.struct_size = old;
    out.camera.width = 12345;
    let s = unsafe { coray_saved_open(a.ptr(), a.1, &mut out) };
    assert_eq!(s, CorayStatus::Ok);
    assert_eq!((out.has_camera, out.camera.width), (1, 12345));
}
