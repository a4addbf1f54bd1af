//! End-to-end tests of the `rigport` CLI (one test binary, modules by area).
#![allow(
    clippy::unwrap_used,
    reason = "test code: a failed unwrap is a failed test"
)]

mod bad_input;
mod common;
mod csci520;
mod demo;
mod gltf_read;
mod gltf_samples;
mod motion;
mod pinocchio;
mod render;
mod skinning;
mod usd;
mod usd_import;
