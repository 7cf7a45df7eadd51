# endorecon GPU worker image (endorecon-worker-cuda:0.1.0), built with the CUDA toolkit of an
# NVIDIA CUDA base image. V100 (sm_70) nodes need CUDA 11.8 or 12.x (CUDA 13 dropped Volta):
#   docker build -f deploy/containers/endorecon-worker-cuda.Dockerfile -t endorecon-worker-cuda:0.1.0 .
#   docker build -f deploy/containers/endorecon-worker-cuda.Dockerfile --build-arg CUDA_VERSION=11.8.0 \
#     --build-arg CUDA_HOST_COMPILER=g++-11 -t endorecon-worker-cuda:0.1.0-cuda11.8 .
# NVIDIA publishes its CUDA images on Ubuntu, not Debian; the toolkit (nvcc, headers, static
# runtime) is taken from one and everything else comes from Debian 12 packages, exactly what
# scripts/install-deps installs. CUDA 11.8 accepts host GCC up to 11, hence g++-11 for it. The CUDA
# runtime is linked statically, so the runtime stage needs only the driver, which the NVIDIA
# container toolkit mounts at run time.
ARG CUDA_VERSION=12.4.1
FROM nvidia/cuda:${CUDA_VERSION}-devel-ubuntu22.04 AS cuda

FROM debian:12 AS build
ARG CUDA_HOST_COMPILER=g++
# Empty: cmake/Cuda.cmake's cluster list for the toolkit's version (SASS for 7.0 (not with CUDA 13),
# 7.5, 8.0, 8.6 and 9.0 with its PTX); --build-arg CUDA_ARCHITECTURES="70-real;80" picks others.
ARG CUDA_ARCHITECTURES=
COPY --from=cuda /usr/local/cuda /usr/local/cuda
COPY . /src
ENV PATH=/usr/local/cuda/bin:$PATH
RUN /src/scripts/install-deps \
 && if [ "$CUDA_HOST_COMPILER" != g++ ]; then apt-get install -y -qq --no-install-recommends "$CUDA_HOST_COMPILER"; fi \
 && cmake -S /src -B /build -G Ninja -DCMAKE_BUILD_TYPE=Release -DENDORECON_CUDA=ON -DENDORECON_NATIVE=OFF \
      -DENDORECON_TESTS=OFF -DENDORECON_BENCH=OFF -DENDORECON_CUDA_ARCHITECTURES="$CUDA_ARCHITECTURES" \
      -DCMAKE_CUDA_HOST_COMPILER="$CUDA_HOST_COMPILER" \
 && cmake --build /build --target endorecon-worker endorecon

FROM debian:12-slim
COPY scripts/install-deps /usr/local/lib/endorecon/install-deps
RUN /usr/local/lib/endorecon/install-deps --runtime worker && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --user-group --home-dir /scratch endorecon
COPY --from=build /build/worker/runtime/endorecon-worker /usr/local/bin/endorecon-worker
COPY --from=build /build/client/endorecon /usr/local/bin/endorecon
ENV NVIDIA_VISIBLE_DEVICES=all NVIDIA_DRIVER_CAPABILITIES=compute,utility
USER 10001:10001
EXPOSE 9465
CMD ["endorecon-worker", "--help"]
