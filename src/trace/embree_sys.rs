//! Minimal FFI bindings to the system's Embree 3 (`libembree3`, Debian `libembree-dev`), only
//! what [`super::embree::EmbreeTracer`] and [`super::embree_instances::EmbreeInstances`] call. Layouts follow the 3.13 headers
//! (`embree3/rtcore_*.h`) as Debian builds them: `RTC_MAX_INSTANCE_LEVEL_COUNT = 1`,
//! `RTC_MIN_WIDTH = 0`, so the intersection context is `{flags, filter, instID[1]}`. Size and
//! alignment assertions below pin every struct to its C twin.
//!
//! Why not the `embree` crate (0.3.8, the newest 0.3.x, Embree 3): its `Scene` has no setter for
//! the scene flags or the build quality (so no robust mode), its packets stop at 4 wide
//! (`occluded4`, no `rtcOccluded8`), its scene borrows its device (`Scene<'a>`,
//! `commit(&'a self)`), which a tracer owning both cannot hold without self-reference, and it
//! brings cgmath 0.18. Its `sys` module is the same declarations as here. These ~20
//! declarations are the whole surface we use, checked against the 3.13 headers, and add no
//! dependency. The library is linked by the `#[link]` attribute below, which exists only in a
//! build with the `embree` feature (this module is compiled only then), so the default build
//! needs no Embree at all.

#![allow(non_camel_case_types, non_snake_case, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};

pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;

pub const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
pub const RTC_GEOMETRY_TYPE_INSTANCE: c_uint = 121;
pub const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
pub const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
pub const RTC_FORMAT_UINT3: c_uint = 0x5003;
pub const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
pub const RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR: c_uint = 0x9234;
pub const RTC_SCENE_FLAG_DYNAMIC: c_uint = 1 << 0;
pub const RTC_SCENE_FLAG_ROBUST: c_uint = 1 << 2;
pub const RTC_BUILD_QUALITY_LOW: c_uint = 0;
pub const RTC_BUILD_QUALITY_HIGH: c_uint = 2;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
pub const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;
pub const RTC_ERROR_NONE: c_uint = 0;
pub const RTC_DEVICE_PROPERTY_VERSION: c_uint = 0;

/// `struct RTCIntersectContext` (3.13, one instance level, no min width).
#[repr(C)]
pub struct RTCIntersectContext {
    pub flags: c_uint,
    pub filter: *const c_void,
    pub instID: [c_uint; 1],
}

impl RTCIntersectContext {
    /// `rtcInitIntersectContext` (an inline function in the header).
    pub fn new(flags: c_uint) -> RTCIntersectContext {
        RTCIntersectContext {
            flags,
            filter: std::ptr::null(),
            instID: [RTC_INVALID_GEOMETRY_ID],
        }
    }
}

/// `struct RTCRay`.
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
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

/// `struct RTCHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: c_uint,
    pub geomID: c_uint,
    pub instID: [c_uint; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// `struct RTCRay8` (structure of arrays, 32-byte aligned).
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
    pub mask: [c_uint; 8],
    pub id: [c_uint; 8],
    pub flags: [c_uint; 8],
}

/// `struct RTCHit8` (structure of arrays, 32-byte aligned; one instance level).
#[repr(C, align(32))]
#[derive(Clone, Copy, Default)]
pub struct RTCHit8 {
    pub Ng_x: [f32; 8],
    pub Ng_y: [f32; 8],
    pub Ng_z: [f32; 8],
    pub u: [f32; 8],
    pub v: [f32; 8],
    pub primID: [c_uint; 8],
    pub geomID: [c_uint; 8],
    pub instID: [[c_uint; 8]; 1],
}

/// `struct RTCRayHit8`.
#[repr(C, align(32))]
#[derive(Clone, Copy, Default)]
pub struct RTCRayHit8 {
    pub ray: RTCRay8,
    pub hit: RTCHit8,
}

/// The packets' valid mask: -1 active, 0 inactive (32-byte aligned as the header asks).
#[repr(C, align(32))]
#[derive(Clone, Copy, Default)]
pub struct Valid8(pub [c_int; 8]);

#[link(name = "embree3")]
extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> c_uint;
    pub fn rtcGetDeviceProperty(device: RTCDevice, prop: c_uint) -> isize;

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: c_uint);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_uint);
    pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    pub fn rtcCommitScene(scene: RTCScene);

    pub fn rtcNewGeometry(device: RTCDevice, kind: c_uint) -> RTCGeometry;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: c_uint);
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcSetGeometryInstancedScene(geometry: RTCGeometry, scene: RTCScene);
    pub fn rtcSetGeometryTransform(
        geometry: RTCGeometry,
        time_step: c_uint,
        format: c_uint,
        xfm: *const c_void,
    );

    pub fn rtcIntersect1(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
    );
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect8(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit8,
    );
    pub fn rtcOccluded8(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        ray: *mut RTCRay8,
    );
}

// The C layouts (rtcore_ray.h, rtcore_common.h on x86-64).
const _: () = {
    assert!(std::mem::size_of::<RTCIntersectContext>() == 24);
    assert!(std::mem::size_of::<RTCRay>() == 48);
    assert!(std::mem::size_of::<RTCHit>() == 32);
    assert!(std::mem::size_of::<RTCRayHit>() == 80);
    assert!(std::mem::offset_of!(RTCRayHit, hit) == 48);
    assert!(std::mem::align_of::<RTCRay>() == 16);
    assert!(std::mem::size_of::<RTCRay8>() == 384);
    assert!(std::mem::align_of::<RTCRay8>() == 32);
    assert!(std::mem::offset_of!(RTCRay8, tfar) == 256);
    assert!(std::mem::size_of::<RTCHit8>() == 256);
    assert!(std::mem::offset_of!(RTCHit8, primID) == 160);
    assert!(std::mem::offset_of!(RTCHit8, geomID) == 192);
    assert!(std::mem::size_of::<RTCRayHit8>() == 640);
    assert!(std::mem::offset_of!(RTCRayHit8, hit) == 384);
};
