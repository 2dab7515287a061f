/* Globals: prepareScene, SceneView. */
// A small point-cloud viewer: WebGL points and lines with an orbit camera (left drag: orbit,
// right or shift drag: pan, wheel: zoom), or the same drawing on a 2D canvas without WebGL.
'use strict';
const SCENE_BACKGROUND = [0.075, 0.094, 0.133];

const Mat4 = {
  multiply(a, b) {
    const out = new Float32Array(16);
    for (let c = 0; c < 4; ++c) {
      for (let r = 0; r < 4; ++r) {
        let sum = 0;
        for (let k = 0; k < 4; ++k) sum += a[k * 4 + r] * b[c * 4 + k];
        out[c * 4 + r] = sum;
      }
    }
    return out;
  },
  perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), out = new Float32Array(16);
    out[0] = f / aspect; out[5] = f; out[10] = (far + near) / (near - far); out[11] = -1;
    out[14] = (2 * far * near) / (near - far);
    return out;
  },
  lookAt(eye, target, up) {
    const z = Vec3.normalize(Vec3.sub(eye, target));
    const x = Vec3.normalize(Vec3.cross(up, z));
    const y = Vec3.cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
                             -Vec3.dot(x, eye), -Vec3.dot(y, eye), -Vec3.dot(z, eye), 1]);
  },
};

const Vec3 = {
  add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
  sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
  scale: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
  dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
  cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
  normalize: (a) => { const n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; },
};

function decodeBase64(text) {
  const binary = atob(text || '');
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; ++i) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// Turns the embedded scene into vertex arrays shared by every view.
function prepareScene(scene) {
  const positions = new Float32Array(decodeBase64(scene.points).buffer);
  const colors = decodeBase64(scene.colors);
  const lineVertices = [], lineColors = [];
  const cameras = scene.cameras || [];
  const push = (p, color) => { lineVertices.push(p[0], p[1], p[2]); lineColors.push(...color); };
  cameras.forEach((camera, index) => {
    const t = cameras.length > 1 ? index / (cameras.length - 1) : 0;
    // From cyan (first) to magenta (last): the order of the sequence.
    const color = [Math.round(60 + 195 * t), Math.round(210 - 130 * t), 255];
    const k = camera.k;
    const corners = [0, 1, 2, 3].map((i) => [k[3 * i], k[3 * i + 1], k[3 * i + 2]]);
    for (let i = 0; i < 4; ++i) {
      push(camera.c, color); push(corners[i], color);
      push(corners[i], color); push(corners[(i + 1) % 4], color);
    }
  });
  const trajectory = [], trajectoryColors = [];
  for (let i = 0; i + 1 < cameras.length; ++i) {
    trajectory.push(...cameras[i].c, ...cameras[i + 1].c);
    trajectoryColors.push(255, 170, 40, 255, 170, 40);
  }
  return { positions, colors, numPoints: positions.length / 3,
           frustums: new Float32Array(lineVertices), frustumColors: new Uint8Array(lineColors),
           trajectory: new Float32Array(trajectory), trajectoryColors: new Uint8Array(trajectoryColors),
           radius: scene.radius || 1, up: scene.up || [0, 1, 0], forward: scene.forward || [0, 0, 1] };
}

const VERTEX_SHADER = `
attribute vec3 position;
attribute vec3 color;
uniform mat4 mvp;
uniform float pointSize;
varying vec3 vColor;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  gl_PointSize = pointSize;
  vColor = color;
}`;
const FRAGMENT_SHADER = `
precision mediump float;
varying vec3 vColor;
void main() { gl_FragColor = vec4(vColor, 1.0); }`;

class SceneView {
  // options: {yaw, pitch (degrees), interactive, pointSize}
  constructor(canvas, prepared, options) {
    this.canvas = canvas;
    this.data = prepared;
    this.options = options;
    this.showCameras = true;
    this.showTrajectory = true;
    this.pointScale = 1;
    this.reset();
    this.gl = null;
    try {
      this.gl = canvas.getContext('webgl', { antialias: true, preserveDrawingBuffer: false });
    } catch (error) {
      this.gl = null;
    }
    if (this.gl) this.initGl(); else this.ctx = canvas.getContext('2d');
    if (options.interactive) this.attachMouse();
  }

  reset() {
    this.yaw = this.options.yaw * Math.PI / 180;
    this.pitch = this.options.pitch * Math.PI / 180;
    this.target = [0, 0, 0];
    // The sphere that holds the cameras just fits the vertical field of view.
    this.distance = this.data.radius / Math.sin(Math.PI / 8);
  }

  initGl() {
    const gl = this.gl;
    const compile = (type, source) => {
      const shader = gl.createShader(type);
      gl.shaderSource(shader, source);
      gl.compileShader(shader);
      if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
      return shader;
    };
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, VERTEX_SHADER));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, FRAGMENT_SHADER));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    this.program = program;
    this.attributes = { position: gl.getAttribLocation(program, 'position'),
                        color: gl.getAttribLocation(program, 'color') };
    this.uniforms = { mvp: gl.getUniformLocation(program, 'mvp'),
                      pointSize: gl.getUniformLocation(program, 'pointSize') };
    const buffer = (array) => {
      const handle = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, handle);
      gl.bufferData(gl.ARRAY_BUFFER, array, gl.STATIC_DRAW);
      return handle;
    };
    const d = this.data;
    this.buffers = {
      points: [buffer(d.positions), buffer(d.colors), d.numPoints],
      frustums: [buffer(d.frustums), buffer(d.frustumColors), d.frustums.length / 3],
      trajectory: [buffer(d.trajectory), buffer(d.trajectoryColors), d.trajectory.length / 3],
    };
  }

  // Eye position on a sphere around the target: yaw about `up`, pitch above the horizon;
  // yaw 0 looks along `forward`.
  eye() {
    const f = this.data.forward, u = this.data.up;
    const r = Vec3.normalize(Vec3.cross(f, u));
    const horizontal = Vec3.add(Vec3.scale(f, Math.cos(this.yaw)), Vec3.scale(r, Math.sin(this.yaw)));
    const direction = Vec3.add(Vec3.scale(horizontal, -Math.cos(this.pitch)), Vec3.scale(u, Math.sin(this.pitch)));
    return Vec3.add(this.target, Vec3.scale(direction, this.distance));
  }

  matrix() {
    const width = this.canvas.width, height = this.canvas.height;
    const radius = this.data.radius;
    const near = Math.max(this.distance - 4 * radius, this.distance * 0.01, 1e-6);
    const far = this.distance + 20 * radius;
    const projection = Mat4.perspective(Math.PI / 4, width / Math.max(height, 1), near, far);
    return Mat4.multiply(projection, Mat4.lookAt(this.eye(), this.target, this.data.up));
  }

  resize() {
    const ratio = window.devicePixelRatio || 1;
    const width = Math.round(this.canvas.clientWidth * ratio), height = Math.round(this.canvas.clientHeight * ratio);
    if (width > 0 && height > 0 && (this.canvas.width !== width || this.canvas.height !== height)) {
      this.canvas.width = width;
      this.canvas.height = height;
    }
  }

  pointSize() {
    const ratio = window.devicePixelRatio || 1;
    const base = this.data.numPoints > 100000 ? 1.6 : this.data.numPoints > 20000 ? 2.2 : 3.0;
    return base * ratio * this.pointScale * (this.options.small ? 0.8 : 1);
  }

  render() {
    this.resize();
    const mvp = this.matrix();
    if (this.gl) this.renderGl(mvp); else this.render2d(mvp);
  }

  renderGl(mvp) {
    const gl = this.gl;
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(SCENE_BACKGROUND[0], SCENE_BACKGROUND[1], SCENE_BACKGROUND[2], 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.program);
    gl.uniformMatrix4fv(this.uniforms.mvp, false, mvp);
    gl.uniform1f(this.uniforms.pointSize, this.pointSize());
    const draw = (entry, mode) => {
      const [positions, colors, count] = entry;
      if (count === 0) return;
      gl.bindBuffer(gl.ARRAY_BUFFER, positions);
      gl.enableVertexAttribArray(this.attributes.position);
      gl.vertexAttribPointer(this.attributes.position, 3, gl.FLOAT, false, 0, 0);
      gl.bindBuffer(gl.ARRAY_BUFFER, colors);
      gl.enableVertexAttribArray(this.attributes.color);
      gl.vertexAttribPointer(this.attributes.color, 3, gl.UNSIGNED_BYTE, true, 0, 0);
      gl.drawArrays(mode, 0, count);
    };
    draw(this.buffers.points, gl.POINTS);
    if (this.showCameras) draw(this.buffers.frustums, gl.LINES);
    if (this.showTrajectory) draw(this.buffers.trajectory, gl.LINES);
  }

  render2d(mvp) {
    const ctx = this.ctx, width = this.canvas.width, height = this.canvas.height;
    const bg = SCENE_BACKGROUND.map((c) => Math.round(255 * c));
    ctx.fillStyle = `rgb(${bg[0]},${bg[1]},${bg[2]})`;
    ctx.fillRect(0, 0, width, height);
    const project = (p, i) => {
      const x = p[i], y = p[i + 1], z = p[i + 2];
      const w = mvp[3] * x + mvp[7] * y + mvp[11] * z + mvp[15];
      if (w <= 1e-9) return null;
      return [((mvp[0] * x + mvp[4] * y + mvp[8] * z + mvp[12]) / w + 1) * width / 2,
              (1 - (mvp[1] * x + mvp[5] * y + mvp[9] * z + mvp[13]) / w) * height / 2];
    };
    const d = this.data, size = this.pointSize();
    for (let i = 0; i < d.numPoints; ++i) {
      const q = project(d.positions, 3 * i);
      if (!q) continue;
      ctx.fillStyle = `rgb(${d.colors[3 * i]},${d.colors[3 * i + 1]},${d.colors[3 * i + 2]})`;
      ctx.fillRect(q[0] - size / 2, q[1] - size / 2, size, size);
    }
    const lines = (vertices, colors) => {
      for (let i = 0; i + 5 < vertices.length; i += 6) {
        const a = project(vertices, i), b = project(vertices, i + 3);
        if (!a || !b) continue;
        ctx.strokeStyle = `rgb(${colors[i]},${colors[i + 1]},${colors[i + 2]})`;
        ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
      }
    };
    if (this.showCameras) lines(d.frustums, d.frustumColors);
    if (this.showTrajectory) lines(d.trajectory, d.trajectoryColors);
  }

  // Number of pixels that differ from the background (read back from the drawing buffer).
  countDrawnPixels() {
    const width = this.canvas.width, height = this.canvas.height;
    let pixels;
    if (this.gl) {
      pixels = new Uint8Array(width * height * 4);
      this.gl.readPixels(0, 0, width, height, this.gl.RGBA, this.gl.UNSIGNED_BYTE, pixels);
    } else {
      pixels = this.ctx.getImageData(0, 0, width, height).data;
    }
    const bg = SCENE_BACKGROUND.map((c) => Math.round(255 * c));
    let count = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      if (Math.abs(pixels[i] - bg[0]) + Math.abs(pixels[i + 1] - bg[1]) + Math.abs(pixels[i + 2] - bg[2]) > 6) ++count;
    }
    return count;
  }

  requestRender() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.render(); });
  }

  attachMouse() {
    const canvas = this.canvas;
    let last = null, panning = false;
    canvas.addEventListener('contextmenu', (event) => event.preventDefault());
    canvas.addEventListener('mousedown', (event) => {
      last = [event.clientX, event.clientY];
      panning = event.button === 2 || event.button === 1 || event.shiftKey;
      event.preventDefault();
    });
    window.addEventListener('mouseup', () => { last = null; });
    window.addEventListener('mousemove', (event) => {
      if (!last) return;
      const dx = event.clientX - last[0], dy = event.clientY - last[1];
      last = [event.clientX, event.clientY];
      if (panning) {
        const f = Vec3.normalize(Vec3.sub(this.target, this.eye()));
        const right = Vec3.normalize(Vec3.cross(f, this.data.up));
        const up = Vec3.cross(right, f);
        const perPixel = 2 * this.distance * Math.tan(Math.PI / 8) / canvas.clientHeight;
        this.target = Vec3.add(this.target, Vec3.add(Vec3.scale(right, -dx * perPixel), Vec3.scale(up, dy * perPixel)));
      } else {
        this.yaw -= dx * 0.008;
        this.pitch = Math.max(-1.55, Math.min(1.55, this.pitch + dy * 0.008));
      }
      this.requestRender();
    });
    canvas.addEventListener('wheel', (event) => {
      event.preventDefault();
      this.distance *= Math.exp(Math.max(-0.5, Math.min(0.5, event.deltaY * 0.0015)));
      this.requestRender();
    }, { passive: false });
    canvas.addEventListener('dblclick', () => { this.reset(); this.requestRender(); });
  }
}
