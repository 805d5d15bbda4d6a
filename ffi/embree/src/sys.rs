//! The part of Embree 3.13's C API that coray compares against, declared by
//! hand from <embree3/rtcore.h> (Debian's build: RTC_MAX_INSTANCE_LEVEL_COUNT
//! 1, RTC_MIN_WIDTH 0). The published `embree3-sys` crate was not used: it
//! runs bindgen (libclang) and, with `CI` set, skips linking Embree at all.
#![allow(non_camel_case_types, non_snake_case, missing_docs)]

use core::ffi::{c_char, c_void};

pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;

pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
pub const RTC_GEOMETRY_TYPE_CONE_LINEAR_CURVE: u32 = 15;
pub const RTC_GEOMETRY_TYPE_SPHERE_POINT: u32 = 50;
pub const RTC_BUFFER_TYPE_INDEX: u32 = 0;
pub const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
pub const RTC_BUFFER_TYPE_FLAGS: u32 = 32;
pub const RTC_FORMAT_UCHAR: u32 = 0x1001;
pub const RTC_FORMAT_UINT: u32 = 0x5001;
pub const RTC_FORMAT_UINT3: u32 = 0x5003;
pub const RTC_FORMAT_FLOAT3: u32 = 0x9003;
pub const RTC_FORMAT_FLOAT4: u32 = 0x9004;
pub const RTC_SCENE_FLAG_ROBUST: u32 = 1 << 2;
pub const RTC_BUILD_QUALITY_HIGH: u32 = 2;
pub const RTC_CURVE_FLAG_NEIGHBOR_LEFT: u8 = 1;
pub const RTC_CURVE_FLAG_NEIGHBOR_RIGHT: u8 = 2;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: u32 = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: u32 = 1;

#[repr(C)]
pub struct RTCIntersectContext {
    pub flags: u32,
    pub filter: *const c_void,
    pub instID: [u32; 1],
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: u32,
    pub geomID: u32,
    pub instID: [u32; 1],
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

#[repr(C, align(32))]
#[derive(Clone, Copy, Default)]
pub struct RTCRay8 {
    pub org_x: [f32; 8],
    pub org_y: [f32; 8],
    pub org_z: [f32; 8],
    pub tnear: [f32; 8],
    pub dir_x: [f32; 8],
    pub dir_y: [f32; 8],
    pub dir_z: [f32; 8],
    pub time: [f32; 8],
    pub tfar: [f32; 8],
    pub mask: [u32; 8],
    pub id: [u32; 8],
    pub flags: [u32; 8],
}

#[repr(C, align(32))]
#[derive(Clone, Copy, Default)]
pub struct RTCHit8 {
    pub Ng_x: [f32; 8],
    pub Ng_y: [f32; 8],
    pub Ng_z: [f32; 8],
    pub u: [f32; 8],
    pub v: [f32; 8],
    pub primID: [u32; 8],
    pub geomID: [u32; 8],
    pub instID: [[u32; 8]; 1],
}

#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RTCRayHit8 {
    pub ray: RTCRay8,
    pub hit: RTCHit8,
}

/// `bool (*)(void *ptr, ssize_t bytes, bool post)`: Embree's device memory
/// monitor; `bytes` is positive for an allocation, negative for a release.
pub type RTCMemoryMonitorFunction =
    Option<unsafe extern "C" fn(ptr: *mut c_void, bytes: isize, post: bool) -> bool>;

const _: () = {
    assert!(core::mem::size_of::<RTCRay8>() == 384);
    assert!(core::mem::size_of::<RTCHit8>() == 256);
    assert!(core::mem::size_of::<RTCRay>() == 48);
    assert!(core::mem::size_of::<RTCHit>() == 32);
    assert!(core::mem::size_of::<RTCRayHit>() == 80);
};

extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> u32;
    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: u32);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: u32);
    pub fn rtcCommitScene(scene: RTCScene);
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcNewGeometry(device: RTCDevice, ty: u32) -> RTCGeometry;
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        ty: u32,
        slot: u32,
        format: u32,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcAttachGeometryByID(scene: RTCScene, geometry: RTCGeometry, id: u32);
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcIntersect1(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
    );
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect8(
        valid: *const i32,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit8,
    );
    pub fn rtcOccluded8(
        valid: *const i32,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        ray: *mut RTCRay8,
    );
    pub fn rtcSetDeviceMemoryMonitorFunction(
        device: RTCDevice,
        monitor: RTCMemoryMonitorFunction,
        user: *mut c_void,
    );
}
