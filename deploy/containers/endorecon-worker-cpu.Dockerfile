# endorecon CPU worker image (endorecon-worker-cpu:0.1.0): for clusters without GPUs, or to run the
# CPU preset next to GPU workers. Build from the repository root:
#   docker build -f deploy/containers/endorecon-worker-cpu.Dockerfile -t endorecon-worker-cpu:0.1.0 .
# The build stage installs exactly what scripts/install-deps installs; the runtime stage only the
# shared libraries the binaries load (scripts/install-deps --runtime IMAGE), all Debian 12 packages.
# Not -march=native: the image runs on whatever x86-64 node the scheduler picks.
FROM debian:12 AS build
COPY . /src
RUN /src/scripts/install-deps \
 && cmake -S /src -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release -DENDORECON_CUDA=OFF -DENDORECON_NATIVE=OFF \
      -DENDORECON_TESTS=OFF -DENDORECON_BENCH=OFF \
 && cmake --build /build --target endorecon-worker endorecon

FROM debian:12-slim
COPY scripts/install-deps /usr/local/lib/endorecon/install-deps
RUN /usr/local/lib/endorecon/install-deps --runtime worker && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --user-group --home-dir /scratch endorecon
COPY --from=build /build/worker/runtime/endorecon-worker /usr/local/bin/endorecon-worker
COPY --from=build /build/client/endorecon /usr/local/bin/endorecon
USER 10001:10001
EXPOSE 9465
CMD ["endorecon-worker", "--help"]
