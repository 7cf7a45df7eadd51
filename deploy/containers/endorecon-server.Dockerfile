# endorecon-server image (the name Kubernetes manifests use: endorecon-server:0.1.0). Build from the
# repository root:
#   docker build -f deploy/containers/endorecon-server.Dockerfile -t endorecon-server:0.1.0 .
# The build stage installs exactly what scripts/install-deps installs; the runtime stage only the
# shared libraries the binaries load (scripts/install-deps --runtime IMAGE), all Debian 12 packages.
FROM debian:12 AS build
COPY . /src
RUN /src/scripts/install-deps \
 && cmake -S /src -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release -DENDORECON_CUDA=OFF -DENDORECON_NATIVE=OFF \
      -DENDORECON_TESTS=OFF -DENDORECON_BENCH=OFF \
 && cmake --build /build --target endorecon-server

FROM debian:12-slim
COPY scripts/install-deps /usr/local/lib/endorecon/install-deps
RUN /usr/local/lib/endorecon/install-deps --runtime server && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --user-group --home-dir /data endorecon
COPY --from=build /build/server/endorecon-server /usr/local/bin/endorecon-server
USER 10001:10001
EXPOSE 50051 50052 9464
CMD ["endorecon-server", "--help"]
