// The 3D tissue surface of one frame as a WebGL mesh: the frame's depth map back-projected on a
// coarse pixel grid (data.surface, written by eval::WriteReport), coloured by the rendered colour or
// by the uncertainty, lit from the viewer. Drag rotates about the surface, the wheel zooms,
// double-click resets. Hand-written: a few dozen lines of WebGL need no 3D library.
"use strict";
class SurfaceViewer {
  constructor(canvas, surface, inferno) {
    this.canvas = canvas;
    this.surface = surface;
    this.inferno = inferno;
    this.colouring = "rgb";
    this.frame = 0;
    this.meshes = new Map();
    const gl = canvas.getContext("webgl", { preserveDrawingBuffer: true, antialias: true });
    if (!gl) throw new Error("WebGL is not available in this browser");
    this.gl = gl;
    this.program = this.buildProgram();
    const first = this.mesh(0);
    this.target = first.centre;
    this.radius = Math.max(first.radius, 1e-6);
    const eye = surface.view.eye;
    const back = [eye[0] - this.target[0], eye[1] - this.target[1], eye[2] - this.target[2]];
    this.home = { distance: 1.15 * Math.max(Math.hypot(...back), 2 * this.radius) };
    this.axes = this.frameAxes(back, surface.view.up);
    this.reset();
    this.attachMouse();
  }

  buildProgram() {
    const gl = this.gl;
    const compile = (type, source) => {
      const shader = gl.createShader(type);
      gl.shaderSource(shader, source);
      gl.compileShader(shader);
      if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
      return shader;
    };
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, `
      attribute vec3 position; attribute vec3 normal; attribute vec3 colour;
      uniform mat4 projection_view; varying vec3 v_position; varying vec3 v_normal; varying vec3 v_colour;
      void main() {
        v_position = position; v_normal = normal; v_colour = colour;
        gl_Position = projection_view * vec4(position, 1.0);
      }`));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, `
      precision mediump float;
      uniform vec3 eye; varying vec3 v_position; varying vec3 v_normal; varying vec3 v_colour;
      void main() {
        vec3 to_eye = normalize(eye - v_position);
        float light = 0.35 + 0.65 * abs(dot(normalize(v_normal), to_eye));
        gl_FragColor = vec4(v_colour * light, 1.0);
      }`));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    return program;
  }

  // Orthonormal right/up/back axes: back points from the surface to the first camera.
  frameAxes(back, up) {
    const normalise = (v) => { const n = Math.hypot(...v) || 1; return v.map((x) => x / n); };
    const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    const b = normalise(Math.hypot(...back) > 0 ? back : [0, 0, 1]);
    const r = normalise(cross(up, b));
    return { right: r, up: cross(b, r), back: b };
  }

  // Vertices, normals, the colourings and triangles of frame `index`, built once and kept.
  mesh(index) {
    if (this.meshes.has(index)) return this.meshes.get(index);
    const data = this.surface.frames[index];
    const [gw, gh] = data.grid;
    const count = gw * gh, stride = this.surface.stride, camera = data.camera, c2w = camera.c2w;
    const depth = new Uint16Array(decodeBase64(data.depth).buffer);
    const rgb = decodeBase64(data.rgb);
    const uncertainty = decodeBase64(data.uncertainty);
    const model = data.model ? decodeBase64(data.model) : null;
    const position = new Float32Array(count * 3), valid = new Uint8Array(count);
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    // Back-projection as eval::BackProject: the ray through the centre of the grid point's pixel, with
    // unit z-depth, from the camera's centre (OpenGL camera: x right, y up, looking down -z).
    for (let j = 0; j < gh; ++j) for (let i = 0; i < gw; ++i) {
      const g = j * gw + i;
      if (depth[g] === 65535) continue;
      valid[g] = 1;
      const z = data.depth_origin + depth[g] * data.depth_step;
      const u = Math.min(i * stride + (stride >> 1), camera.width - 1);
      const v = Math.min(j * stride + (stride >> 1), camera.height - 1);
      const ray = [(u + 0.5 - camera.cx) / camera.fx, -(v + 0.5 - camera.cy) / camera.fy, -1];
      for (let a = 0; a < 3; ++a) {
        const p = c2w[a][3] + z * (c2w[a][0] * ray[0] + c2w[a][1] * ray[1] + c2w[a][2] * ray[2]);
        position[3 * g + a] = p;
        lo[a] = Math.min(lo[a], p);
        hi[a] = Math.max(hi[a], p);
      }
    }
    const distance = (i, j) => Math.hypot(position[3 * i] - position[3 * j], position[3 * i + 1] - position[3 * j + 1],
                                          position[3 * i + 2] - position[3 * j + 2]);
    // Triangles across a depth jump (a tool's edge, a fold) would be long slivers: an edge longer than
    // six times the median neighbour spacing is left open.
    const spacings = [];
    for (let y = 0; y < gh; ++y) for (let x = 0; x + 1 < gw; ++x) {
      const i = y * gw + x;
      if (valid[i] && valid[i + 1]) spacings.push(distance(i, i + 1));
    }
    spacings.sort((a, b) => a - b);
    const limit = 6 * (spacings[spacings.length >> 1] || Infinity);
    const indices = [], normal = new Float32Array(count * 3);
    const addTriangle = (a, b, c) => {
      if (!valid[a] || !valid[b] || !valid[c]) return;
      if (distance(a, b) > limit || distance(b, c) > limit || distance(a, c) > limit) return;
      indices.push(a, b, c);
      const e1 = [0, 1, 2].map((k) => position[3 * b + k] - position[3 * a + k]);
      const e2 = [0, 1, 2].map((k) => position[3 * c + k] - position[3 * a + k]);
      const n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
      for (const v of [a, b, c]) for (let k = 0; k < 3; ++k) normal[3 * v + k] += n[k];
    };
    for (let y = 0; y + 1 < gh; ++y) for (let x = 0; x + 1 < gw; ++x) {
      const i = y * gw + x;
      addTriangle(i, i + gw, i + 1);
      addTriangle(i + 1, i + gw, i + gw + 1);
    }
    const rgbColour = new Float32Array(count * 3);
    for (let i = 0; i < 3 * count; ++i) rgbColour[i] = rgb[i] / 255;
    const heatColour = (levels) => {
      const colour = new Float32Array(count * 3);
      for (let i = 0; i < count; ++i) for (let k = 0; k < 3; ++k) colour[3 * i + k] = this.inferno[3 * levels[i] + k] / 255;
      return colour;
    };
    const gl = this.gl;
    const buffer = (array, target) => {
      const b = gl.createBuffer();
      gl.bindBuffer(target || gl.ARRAY_BUFFER, b);
      gl.bufferData(target || gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
      return b;
    };
    const centre = lo.map((v, a) => (v + hi[a]) / 2);
    const mesh = {
      position: buffer(position), normal: buffer(normal),
      colour: { rgb: buffer(rgbColour), uncertainty: buffer(heatColour(uncertainty)),
                model: model ? buffer(heatColour(model)) : null },
      indices: buffer(new Uint16Array(indices), gl.ELEMENT_ARRAY_BUFFER), count: indices.length,
      centre: Number.isFinite(centre[0]) ? centre : [0, 0, 0],
      radius: Number.isFinite(centre[0]) ? Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2 : 1,
    };
    this.meshes.set(index, mesh);
    return mesh;
  }

  // The first camera's view turned a little sideways and down, so the surface reads as 3D at once.
  reset() {
    this.yaw = 0.45;
    this.pitch = 0.35;
    this.distance = this.home.distance;
    this.draw();
  }

  showFrame(index) { this.frame = index; this.draw(); }
  setColouring(colouring) { this.colouring = colouring; this.draw(); }
  triangles() { return this.mesh(this.frame).count / 3; }

  attachMouse() {
    let last = null;
    this.canvas.addEventListener("mousedown", (e) => { last = [e.clientX, e.clientY]; e.preventDefault(); });
    window.addEventListener("mouseup", () => { last = null; });
    window.addEventListener("mousemove", (e) => {
      if (!last) return;
      this.yaw -= (e.clientX - last[0]) * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + (e.clientY - last[1]) * 0.01));
      last = [e.clientX, e.clientY];
      this.draw();
    });
    this.canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.distance = Math.max(this.radius * 0.2, this.distance * Math.exp(e.deltaY * 0.001));
      this.draw();
    }, { passive: false });
    this.canvas.addEventListener("dblclick", () => this.reset());
  }

  eye() {
    const { right, up, back } = this.axes;
    const c = Math.cos(this.pitch), s = Math.sin(this.pitch);
    const along = [c * Math.sin(this.yaw), s, c * Math.cos(this.yaw)];
    return [0, 1, 2].map((k) => this.target[k] + this.distance *
                                (along[0] * right[k] + along[1] * up[k] + along[2] * back[k]));
  }

  projectionView(eye) {
    const f = eye.map((v, k) => this.target[k] - v);
    const norm = Math.hypot(...f);
    const fw = f.map((v) => v / norm);
    const upHint = this.axes.up;
    let side = [fw[1] * upHint[2] - fw[2] * upHint[1], fw[2] * upHint[0] - fw[0] * upHint[2],
                fw[0] * upHint[1] - fw[1] * upHint[0]];
    const sn = Math.hypot(...side) || 1;
    side = side.map((v) => v / sn);
    const u = [side[1] * fw[2] - side[2] * fw[1], side[2] * fw[0] - side[0] * fw[2], side[0] * fw[1] - side[1] * fw[0]];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // Column-major view matrix (camera looks down -z), then a perspective of 40 degrees.
    const view = [side[0], u[0], -fw[0], 0, side[1], u[1], -fw[1], 0, side[2], u[2], -fw[2], 0,
                  -dot(side, eye), -dot(u, eye), dot(fw, eye), 1];
    const near = Math.max(this.distance * 0.01, this.distance - 4 * this.radius);
    const far = this.distance + 4 * this.radius;
    const t = 1 / Math.tan((40 * Math.PI / 180) / 2), aspect = this.canvas.width / this.canvas.height;
    const projection = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1,
                        0, 0, 2 * far * near / (near - far), 0];
    const out = new Float32Array(16);
    for (let c = 0; c < 4; ++c) for (let r = 0; r < 4; ++r) {
      let sum = 0;
      for (let k = 0; k < 4; ++k) sum += projection[k * 4 + r] * view[c * 4 + k];
      out[c * 4 + r] = sum;
    }
    return out;
  }

  draw() {
    const gl = this.gl, program = this.program, mesh = this.mesh(this.frame);
    const eye = this.eye();
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(16 / 255, 19 / 255, 26 / 255, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(program);
    gl.uniformMatrix4fv(gl.getUniformLocation(program, "projection_view"), false, this.projectionView(eye));
    gl.uniform3fv(gl.getUniformLocation(program, "eye"), eye);
    const attribute = (name, buffer) => {
      const location = gl.getAttribLocation(program, name);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.enableVertexAttribArray(location);
      gl.vertexAttribPointer(location, 3, gl.FLOAT, false, 0, 0);
    };
    attribute("position", mesh.position);
    attribute("normal", mesh.normal);
    attribute("colour", mesh.colour[this.colouring] || mesh.colour.rgb);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, mesh.indices);
    gl.drawElements(gl.TRIANGLES, mesh.count, gl.UNSIGNED_SHORT, 0);
  }
}

function decodeBase64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes;
}
