# The image docs/scale.md's Kubernetes recipe runs: the rigport binary on a slim Debian.
#
#   docker build -t rigport:0.1.0 .
#   docker run --rm -v "$PWD:/data" rigport:0.1.0 convert /data/walk.bvh -o /data/walk.glb
#
# Stage 1 builds the CLI in release mode from this checkout (Cargo.lock pinned); stage 2
# copies only the binary. rigport reads and writes files and links no system library
# beyond the C and C++ runtimes (libstdc++ for meshoptimizer, `--compress meshopt`), both
# in bookworm-slim (apt itself needs libstdc++6), so the runtime needs nothing else. Not
# built in CI (see README).
FROM rust:1-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --locked --bin rigport

FROM debian:bookworm-slim
COPY --from=build /src/target/release/rigport /usr/local/bin/rigport
# Runs as an unprivileged user; a mounted volume must be writable by uid 1000.
RUN useradd --uid 1000 --create-home rigport
USER rigport
WORKDIR /data
ENTRYPOINT ["rigport"]
CMD ["--help"]
