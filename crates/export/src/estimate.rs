//! What the writers will allocate for an asset, estimated before they start (the memory
//! budget, `rigport_model::budget`). Each figure is the peak measured on a large clip
//! (10^6 frames of a 2-joint ASF/AMC: USD text 183 MB written at a 568 MB peak, glTF 36 MB
//! at 185 MB, both including the import) rounded up, per sample and per vertex. A `.usda`
//! is streamed to its file once its text passes 64 MiB, so its estimate is what the writer
//! holds besides the text (10^7 frames of that ASF/AMC: a 1.86 GB file written at a 1.46 GB
//! peak, which is the import's).

use rigport_model::budget::mul;
use rigport_model::Asset;

/// USD text bytes per joint per time sample (translation, rotation and scale values with
/// their time code), and the writer's peak over its text (the text, its growth and the
/// file write).
const USD_BYTES_PER_JOINT_SAMPLE: usize = 100;
const USD_PEAK_OVER_TEXT: u64 = 3;
/// USD text bytes per mesh point (points, normals, texture coordinates, indices) and per
/// influence (joint index and weight).
const USD_BYTES_PER_POINT: usize = 160;
const USD_BYTES_PER_INFLUENCE: usize = 20;

/// glTF binary bytes per joint per key (time, rotation, translation) and per vertex
/// (position, normal, texture coordinates, joints, weights), and the writer's peak over
/// its buffer (buffer, document, container).
const GLTF_BYTES_PER_JOINT_KEY: usize = 36;
const GLTF_BYTES_PER_VERTEX: usize = 80;
const GLTF_PEAK_OVER_BUFFER: u64 = 3;

/// The samples of each clip: its longest track's key count (the writers sample the union
/// of key times, which is at least that).
fn clip_samples(asset: &Asset) -> impl Iterator<Item = usize> + '_ {
    asset
        .clips
        .iter()
        .map(|c| c.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0))
}

/// The most samples of any clip, for messages.
pub fn max_clip_samples(asset: &Asset) -> usize {
    clip_samples(asset).max().unwrap_or(0)
}

/// Estimated peak bytes of writing `asset` as USD text.
pub fn usd_memory(asset: &Asset) -> u64 {
    let joints = asset.skeleton.len().max(1);
    let anim: u64 = clip_samples(asset)
        .map(|n| mul(n, joints).saturating_mul(USD_BYTES_PER_JOINT_SAMPLE as u64))
        .fold(0, u64::saturating_add);
    anim.saturating_add(usd_geometry_text(asset))
        .saturating_mul(USD_PEAK_OVER_TEXT)
}

/// USD text bytes of the meshes' points and influences.
fn usd_geometry_text(asset: &Asset) -> u64 {
    let meshes: u64 = asset
        .meshes
        .iter()
        .map(|m| mul(m.positions.len(), USD_BYTES_PER_POINT))
        .fold(0, u64::saturating_add);
    let influences: u64 = asset
        .skins
        .iter()
        .map(|s| mul(s.influences.entries().len(), USD_BYTES_PER_INFLUENCE))
        .fold(0, u64::saturating_add);
    meshes.saturating_add(influences)
}

/// Bytes per time sample a streaming `.usda` writer holds: the clip's key times (`f64`), the
/// sampled (time code, seconds) pairs, and per track its key times while they are merged
/// (`f32`) and a sign flag per rotation key.
const USD_STREAMED_BYTES_PER_SAMPLE: u64 = 24;
const USD_STREAMED_BYTES_PER_TRACK_KEY: u64 = 5;

/// Estimated peak bytes of writing `asset` to `path` as USD: [`usd_memory`] for a `.usdc`
/// or `.usdz` (encoded in memory), and for a `.usda` (or `.usd`) what the streaming text
/// writer holds: per-sample bookkeeping, the mesh prims' text (a mesh's arrays are one line
/// each) and the 64 MiB text buffer with its file buffer.
pub fn usd_memory_at(asset: &Asset, path: &std::path::Path) -> u64 {
    let in_memory = usd_memory(asset);
    // A text that stays under the spill size is built in memory, as `.usdc` and `.usdz`.
    if crate::usd::encode_is_text(path)
        && in_memory / USD_PEAK_OVER_TEXT > crate::usd::SPILL_BYTES as u64
    {
        usd_streamed_memory(asset).min(in_memory)
    } else {
        in_memory
    }
}

/// The streaming `.usda` writer's estimate (see [`usd_memory_at`]).
fn usd_streamed_memory(asset: &Asset) -> u64 {
    let anim: u64 = asset
        .clips
        .iter()
        .map(|c| {
            let samples = c.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0);
            let track_keys: usize = c.tracks.iter().map(|t| t.times.len()).sum();
            mul(samples, 1)
                .saturating_mul(USD_STREAMED_BYTES_PER_SAMPLE)
                .saturating_add(mul(track_keys, 1).saturating_mul(USD_STREAMED_BYTES_PER_TRACK_KEY))
        })
        .fold(0, u64::saturating_add);
    let buffers = 2 * crate::usd::SPILL_BYTES as u64;
    anim.saturating_add(usd_geometry_text(asset).saturating_mul(USD_PEAK_OVER_TEXT))
        .saturating_add(buffers)
}

/// Estimated peak bytes of writing `asset` as glTF.
pub fn gltf_memory(asset: &Asset) -> u64 {
    let joints = asset.skeleton.len().max(1);
    let anim: u64 = clip_samples(asset)
        .map(|n| mul(n, joints).saturating_mul(GLTF_BYTES_PER_JOINT_KEY as u64))
        .fold(0, u64::saturating_add);
    let meshes: u64 = asset
        .meshes
        .iter()
        .map(|m| mul(m.positions.len(), GLTF_BYTES_PER_VERTEX))
        .fold(0, u64::saturating_add);
    anim.saturating_add(meshes)
        .saturating_mul(GLTF_PEAK_OVER_BUFFER)
}
