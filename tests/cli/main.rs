//! End-to-end tests of the `rigport` CLI (one test binary, modules by area).
#![allow(
    clippy::unwrap_used,
    reason = "test code: a failed unwrap is a failed test"
)]
#![allow(
    clippy::type_complexity,
    clippy::needless_range_loop,
    reason = "test-only readers of reference data favour plain tuples and index loops"
)]

mod bad_input;
mod batch;
mod cloth;
mod cloth_trust;
mod collada;
mod combine;
mod common;
mod compact;
mod csci520;
mod demo;
mod eval_plays;
mod fbx;
mod fbx_blender;
mod fbx_fidelity;
mod fbx_mixamo;
mod fidelity_exceptions;
mod fidelity_frames;
mod fidelity_match;
mod footlock;
mod frame_limit;
mod frames;
mod gltf_read;
mod gltf_samples;
mod ik;
mod ik_chains;
mod materials;
mod memory;
mod message_audit;
mod messages;
mod motion;
mod outputs;
mod pinocchio;
mod refit;
mod render;
mod retarget;
mod root_motion;
mod skin;
mod skinning;
mod three;
mod three_source;
mod units;
mod usd;
mod usd_blendshapes;
mod usd_frames;
mod usd_import;
mod usd_root_motion;
mod usd_topology;
mod usdz;
mod verify;
mod verify_identity;
mod weights;
