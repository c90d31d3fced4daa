// vlab view: draws the lab's visual bodies (scene.json) with three.js r111 and
// moves them with the pose frames of the WebSocket /ws (live) or of
// recording.bin (replay). A frame: float64 time, float64 seq, then float32
// x, y, z, qw, qx, qy, qz per body (little-endian). Read-only: it sends nothing.
// Panels, when scene.json names them: a camera device's pictures (WebSocket
// /camera: float64 time, float64 frame id, uint32 width, uint32 height, then
// a JPEG or PNG file) and plots of a few signals (live: WebSocket /plot,
// float64 time, float64 seq, float64 per signal; replay: plots.bin, rows of
// float64 time and one float64 per signal). Newest wins everywhere.
// Lights: the MJCF's world lights (scene.json's lights: directional,
// spot with its cutoff, castshadow) beside a soft hemisphere light; without
// them one key light. Shadows (three.js shadow maps): the lights with
// castshadow cast, every geom casts and receives (planes only receive); on
// unless `vlab view --no-shadows` (scene.json's shadows: false) or
// shadows=off, and the 'shadows' box turns them off and on.
// URL options: camera=NAME (an MJCF world camera's pose and field of view),
// shadows=off, silhouette (bodies white, world geoms black, no lights: for tests),
// bare (no overlay), clock=manual (a replay advances only by vlabView.tick(ms):
// for tests). Space pauses and resumes, wherever the focus is.
// When the server refuses a WebSocket (its table full), it closes it with a
// reason: the page shows that reason, not only that it is retrying.
(function () {
  'use strict';
  var params = new URLSearchParams(window.location.search);
  var casters = [];  // the lights that cast shadows
  var silhouette = params.has('silhouette');
  if (silhouette || params.has('bare')) document.body.className = 'bare';
  // for tests and for the curious: what has been drawn
  var state = window.vlabView = { ready: false, frames: 0, time: 0, seq: -1, paused: false, error: '',
                                  replayTime: 0, cameraFrames: 0, cameraId: -1, cameraTime: 0, plotSamples: 0,
                                  plotLast: null, plotDrawn: 0, plotEnd: null, refused: '' };
  var renderer, scene, camera, controls, groups = [], latest = null, info = null;
  var recording = null, replayTime = 0, lastWall = 0, manualClock = params.get('clock') === 'manual';
  var plot = null;  // { names, times: [], values: [[]...], dirty }
  var kPlotWindow = 10;  // s of signal shown
  var kPlotColours = ['#ff6b6b', '#4dabf7', '#69db7c', '#ffd43b', '#da77f2', '#ffa94d', '#3bc9db', '#f8f9fa'];

  function setStatus(text) { document.getElementById('status').textContent = text; }
  function fail(text) { state.error = text; setStatus(text); }

  fetch('scene.json').then(function (r) {
    if (r.status === 503) throw new Error('server full (HTTP 503): reload later');
    if (!r.ok) throw new Error('scene.json: HTTP ' + r.status);
    return r.json();
  }).then(build).catch(function (e) { fail('error: ' + e.message); });

  function build(sceneInfo) {
    info = sceneInfo;
    renderer = new THREE.WebGLRenderer({ antialias: !silhouette, preserveDrawingBuffer: true });
    renderer.setPixelRatio(silhouette ? 1 : (window.devicePixelRatio || 1));
    renderer.setSize(window.innerWidth, window.innerHeight);
    document.body.appendChild(renderer.domElement);
    scene = new THREE.Scene();
    scene.background = new THREE.Color(silhouette ? 0x000000 : 0x39424e);
    if (!silhouette) addLights();
    camera = new THREE.PerspectiveCamera(45, window.innerWidth / window.innerHeight, 0.01, 100);
    camera.up.set(0, 0, 1);  // z up, as MuJoCo's world
    var fixed = (info.cameras || []).filter(function (c) { return c.name === params.get('camera'); })[0];
    if (params.get('camera') && !fixed) return fail('no world camera "' + params.get('camera') + '"');
    if (fixed) {
      // a MuJoCo camera looks along its -z with +y up, as a three.js camera does
      camera.fov = fixed.fovy;
      camera.position.set(fixed.pos[0], fixed.pos[1], fixed.pos[2]);
      camera.quaternion.set(fixed.quat[1], fixed.quat[2], fixed.quat[3], fixed.quat[0]);
      camera.updateProjectionMatrix();
    } else {
      camera.position.set(2.2, -1.6, 1.5);
      controls = new THREE.OrbitControls(camera, renderer.domElement);
      controls.target.set(0.3, 0, 0.6);
      controls.update();
    }
    groups = info.bodies.map(function (name) {
      var g = new THREE.Group();
      g.name = name;
      scene.add(g);
      return g;
    });
    var textures = {};
    info.geoms.forEach(function (geom) {
      var object = makeGeom(geom, makeMaterial(geom, textures));
      if (!object) return;
      object.castShadow = !silhouette && geom.type !== 'plane';
      object.receiveShadow = !silhouette;
      object.name = geom.name;
      object.position.set(geom.pos[0], geom.pos[1], geom.pos[2]);
      object.quaternion.set(geom.quat[1], geom.quat[2], geom.quat[3], geom.quat[0]);
      (geom.body >= 0 ? groups[geom.body] : scene).add(object);
    });
    window.addEventListener('resize', function () {
      camera.aspect = window.innerWidth / window.innerHeight;
      camera.updateProjectionMatrix();
      renderer.setSize(window.innerWidth, window.innerHeight);
    });
    // Space toggles wherever the focus is: a focused button (the pause button, once clicked) would
    // otherwise also take the key as a click and undo the toggle, a focused select open its list
    var pause = document.getElementById('pause');
    pause.onclick = function () { togglePause(); pause.blur(); };
    window.addEventListener('keydown', function (e) {
      if (e.code !== 'Space') return;
      e.preventDefault();
      if (!e.repeat) togglePause();
    }, true);
    window.addEventListener('keyup', function (e) { if (e.code === 'Space') e.preventDefault(); }, true);
    if (info.camera) startCamera();
    if (info.plots && info.plots.length) startPlots();
    if (info.mode === 'replay') startReplay(); else connect('/ws', function (data) { latest = data; });  // the newest wins
    state.tick = tick;
    state.pose = function (i) {
      var g = groups[i];
      return [g.position.x, g.position.y, g.position.z, g.quaternion.w, g.quaternion.x, g.quaternion.y, g.quaternion.z];
    };
    var box = document.getElementById('shadows');
    box.checked = info.shadows !== false && params.get('shadows') !== 'off';
    box.onchange = function () { setShadows(box.checked); box.blur(); };
    setShadows(box.checked);
    state.ready = true;
    requestAnimationFrame(animate);
  }

  // the MJCF's world lights (scene.json), or a key light where it names none; MuJoCo's
  // intensities are OpenGL's 0-1 diffuse, as three.js's (non-physical) light intensities
  function addLights() {
    scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 0.6));
    var lights = info.lights && info.lights.length ? info.lights :
        [{ pos: [1.0, -1.5, 3.0], dir: [-0.3, 0.5, -1], directional: true, castshadow: true,
           diffuse: [0.7, 0.7, 0.7] }];
    lights.forEach(function (l) {
      var d = l.diffuse, top = Math.max(d[0], d[1], d[2]), colour = new THREE.Color(1, 1, 1), light;
      if (top > 0) colour.setRGB(d[0] / top, d[1] / top, d[2] / top);
      if (l.directional) {
        light = new THREE.DirectionalLight(colour, top);
        // the shadow's box: 4 m across around where the light looks, 8 m deep
        var c = light.shadow.camera;
        c.left = c.bottom = -2; c.right = c.top = 2; c.near = 0.05; c.far = 8;
      } else if (l.cutoff > 0 && l.cutoff < 90) {
        light = new THREE.SpotLight(colour, top, 0, l.cutoff * Math.PI / 180, 0.3);
        light.shadow.camera.near = 0.05;
      } else {
        light = new THREE.PointLight(colour, top);
      }
      light.position.set(l.pos[0], l.pos[1], l.pos[2]);
      if (light.target) {
        light.target.position.set(l.pos[0] + l.dir[0], l.pos[1] + l.dir[1], l.pos[2] + l.dir[2]);
        scene.add(light.target);
      }
      light.shadow.mapSize.set(2048, 2048);
      light.shadow.bias = -0.0005;
      if (l.castshadow) casters.push(light);
      scene.add(light);
    });
  }

  function setShadows(on) {
    state.shadows = on && !silhouette;
    renderer.shadowMap.enabled = state.shadows;
    renderer.shadowMap.type = THREE.PCFSoftShadowMap;
    casters.forEach(function (l) { l.castShadow = state.shadows; });
    // three.js compiles shadows into the materials' programs: rebuild them
    scene.traverse(function (o) {
      if (!o.material) return;
      (Array.isArray(o.material) ? o.material : [o.material]).forEach(function (m) { m.needsUpdate = true; });
    });
  }

  function togglePause() {
    state.paused = !state.paused;
    document.getElementById('pause').textContent = state.paused ? 'resume' : 'pause';
  }

  function makeMaterial(geom, textures) {
    // silhouette: the bodies white, the world black (it still hides what is behind it)
    if (silhouette) return new THREE.MeshBasicMaterial({ color: geom.body >= 0 ? 0xffffff : 0x000000 });
    var rgba = geom.rgba;
    var options = { color: new THREE.Color(rgba[0], rgba[1], rgba[2]), shininess: 20 };
    if (rgba[3] < 1) { options.transparent = true; options.opacity = rgba[3]; }
    var tex = geom.texture >= 0 ? info.textures[geom.texture] : null;
    if (tex && tex.type === '2d') {
      // texture coordinates: MuJoCo's texgen (texgenUv, on the geometry); the pattern repeats
      var t = new THREE.TextureLoader().load('tex/' + geom.texture);
      t.wrapS = t.wrapT = THREE.RepeatWrapping;
      options.map = t;
      options.color = new THREE.Color(1, 1, 1);
      return new THREE.MeshPhongMaterial(options);
    }
    if (tex && tex.type === 'cube' && geom.type === 'box') return cubeMaterials(geom.texture, options, textures);
    return new THREE.MeshPhongMaterial(options);
  }

  // a cube texture: six square faces stacked (+x, -x, +y, -y, +z, -z), the
  // order of a BoxBufferGeometry's groups; each face's image axes are those
  // MuJoCo uses (docs: mjcf/cubes), which are three.js's box UVs
  function cubeMaterials(id, options, textures) {
    var materials = [];
    for (var f = 0; f < 6; ++f) {
      var o = Object.assign({}, options, { color: new THREE.Color(1, 1, 1) });
      materials.push(new THREE.MeshPhongMaterial(o));
    }
    var image = new Image();
    image.onload = function () {
      var w = image.width;
      for (var f = 0; f < 6; ++f) {
        var canvas = document.createElement('canvas');
        canvas.width = canvas.height = w;
        canvas.getContext('2d').drawImage(image, 0, f * w, w, w, 0, 0, w, w);
        materials[f].map = new THREE.CanvasTexture(canvas);
        materials[f].needsUpdate = true;
      }
    };
    image.src = 'tex/' + id;
    return materials;
  }

  // a 2-D texture's coordinates as MuJoCo 2.2.2 generates them (GL_OBJECT_LINEAR in the geom's
  // frame): s = 0.5 scl_x x - 0.5, t = -0.5 scl_y y - 0.5, scl = texrepeat / size (texuniform
  // or a zero size: texrepeat), row 0 of the image at t = 0 (three.js flips: v = 1 - t); the
  // same coordinates as vlab export writes
  function texgenUv(geom, g) {
    var s = geom.size, type = geom.type;
    var size = type === 'sphere' ? [s[0], s[0]] : type === 'capsule' || type === 'cylinder' ? [s[0], s[0]] : [s[0], s[1]];
    var scale = [0, 1].map(function (k) {
      return geom.texuniform || !(size[k] > 0) ? geom.texrepeat[k] : geom.texrepeat[k] / size[k];
    });
    var p = g.attributes.position, uv = new Float32Array(2 * p.count);
    for (var i = 0; i < p.count; ++i) {
      uv[2 * i] = 0.5 * scale[0] * p.getX(i) - 0.5;
      uv[2 * i + 1] = 1.5 + 0.5 * scale[1] * p.getY(i);
    }
    g.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
  }

  // MuJoCo's capsule: a cylinder of half-length h with hemispheres of radius r, along z
  function capsuleGeometry(r, h) {
    var points = [], n = 12, i, a;
    for (i = 0; i <= n; ++i) { a = -Math.PI / 2 + (i / n) * Math.PI / 2; points.push(new THREE.Vector2(r * Math.cos(a), -h + r * Math.sin(a))); }
    for (i = 0; i <= n; ++i) { a = (i / n) * Math.PI / 2; points.push(new THREE.Vector2(r * Math.cos(a), h + r * Math.sin(a))); }
    return new THREE.LatheBufferGeometry(points, 32).rotateX(Math.PI / 2);
  }

  function makeGeom(geom, material) {
    var s = geom.size, g;
    switch (geom.type) {
      case 'box': g = new THREE.BoxBufferGeometry(2 * s[0], 2 * s[1], 2 * s[2]); break;
      case 'sphere': g = new THREE.SphereBufferGeometry(s[0], 32, 16); break;
      case 'ellipsoid': g = new THREE.SphereBufferGeometry(1, 32, 16).scale(s[0], s[1], s[2]); break;
      case 'cylinder': g = new THREE.CylinderBufferGeometry(s[0], s[0], 2 * s[1], 32).rotateX(Math.PI / 2); break;
      case 'capsule': g = capsuleGeometry(s[0], s[1]); break;
      case 'plane': g = new THREE.PlaneBufferGeometry(2 * (s[0] || 10), 2 * (s[1] || 10)); break;
      case 'mesh': g = new THREE.BufferGeometry(); loadMesh(geom.mesh, g); break;
      default: return null;
    }
    var tex = geom.texture >= 0 ? info.textures[geom.texture] : null;
    if (tex && tex.type === '2d' && geom.type !== 'mesh' && !silhouette) texgenUv(geom, g);
    return new THREE.Mesh(g, material);
  }

  function loadMesh(id, geometry) {
    fetch('mesh/' + id).then(function (r) {
      if (!r.ok) throw new Error('mesh ' + id + ': HTTP ' + r.status);
      return r.arrayBuffer();
    }).then(function (buffer) {
      var counts = new Uint32Array(buffer, 0, 2);
      var vertices = new Float32Array(buffer, 8, 3 * counts[0]);
      var faces = new Uint32Array(buffer, 8 + 12 * counts[0], 3 * counts[1]);
      geometry.setAttribute('position', new THREE.BufferAttribute(vertices, 3));
      geometry.setIndex(new THREE.BufferAttribute(faces, 1));
      geometry.computeVertexNormals();
    }).catch(function (e) { fail('error: ' + e.message); });
  }

  // a WebSocket that reconnects; a refusal's reason (close code 1013: the server is full) is shown,
  // and retried less often than a lost connection
  var refusals = {};  // path -> the server's reason, while that WebSocket is refused
  function showRefusals() {
    state.refused = Object.keys(refusals).map(function (p) { return refusals[p]; }).join('; ');
    setStatus(state.refused ? state.refused + '; retrying in 5 s' : '');
  }
  function connect(path, onData) {
    var ws = new WebSocket((window.location.protocol === 'https:' ? 'wss://' : 'ws://') + window.location.host + path);
    ws.binaryType = 'arraybuffer';
    ws.onopen = function () { delete refusals[path]; showRefusals(); };
    ws.onmessage = function (event) { onData(event.data); };
    ws.onclose = function (event) {
      var refused = event.code === 1013;
      if (refused) {
        refusals[path] = event.reason || 'server full';
        showRefusals();
      } else {
        delete refusals[path];
        setStatus('disconnected, retrying');
      }
      setTimeout(function () { connect(path, onData); }, refused ? 5000 : 1000);
    };
  }

  // ---- the camera panel: one picture decoding at a time, the newest waiting
  function startCamera() {
    var img = document.getElementById('camera'), pending = null, busy = false, url = null;
    document.getElementById('camera-panel').style.display = 'block';
    document.getElementById('camera-caption').textContent = 'camera ' + info.camera.name;
    function show(data) {
      var head = new DataView(data, 0, 24), bytes = new Uint8Array(data, 24);
      var jpeg = bytes.length > 1 && bytes[0] === 0xff && bytes[1] === 0xd8;
      busy = true;
      var next = URL.createObjectURL(new Blob([bytes], { type: jpeg ? 'image/jpeg' : 'image/png' }));
      img.onload = function () {
        if (url) URL.revokeObjectURL(url);
        url = next;
        state.cameraId = head.getFloat64(8, true);
        state.cameraTime = head.getFloat64(0, true);
        ++state.cameraFrames;
        document.getElementById('camera-caption').textContent = 'camera ' + info.camera.name + ', frame ' +
            state.cameraId + ', t = ' + state.cameraTime.toFixed(3) + ' s';
        busy = false;
        if (pending) { var p = pending; pending = null; show(p); }
      };
      img.onerror = function () { URL.revokeObjectURL(next); busy = false; fail('camera: a picture did not decode'); };
      img.src = next;
    }
    connect('/camera', function (data) {
      if (state.paused || data.byteLength <= 24) return;
      if (busy) pending = data; else show(data);
    });
  }

  // ---- the plot panel: the last kPlotWindow seconds of each signal
  function startPlots() {
    document.getElementById('plot-panel').style.display = 'block';
    var n = info.plots.length;
    plot = { names: info.plots, times: [], values: info.plots.map(function () { return []; }), dirty: true };
    if (info.mode === 'replay') {
      fetch('plots.bin').then(function (r) {
        if (!r.ok) throw new Error('plots.bin: HTTP ' + r.status);
        return r.arrayBuffer();
      }).then(function (buffer) {
        var v = new Float64Array(buffer), rows = v.length / (n + 1);
        for (var k = 0; k < rows; ++k) {
          plot.times.push(v[k * (n + 1)]);
          for (var i = 0; i < n; ++i) plot.values[i].push(v[k * (n + 1) + 1 + i]);
        }
        state.plotSamples = rows;
        plot.dirty = true;
      }).catch(function (e) { fail('error: ' + e.message); });
      return;
    }
    connect('/plot', function (data) {
      if (state.paused || data.byteLength !== 8 * (n + 2)) return;
      var v = new Float64Array(data);
      if (plot.times.length && v[0] <= plot.times[plot.times.length - 1]) {  // the lab restarted: start afresh
        if (v[0] < plot.times[plot.times.length - 1]) { plot.times = []; plot.values = plot.values.map(function () { return []; }); }
        else return;
      }
      plot.times.push(v[0]);
      for (var i = 0; i < n; ++i) plot.values[i].push(v[2 + i]);
      while (plot.times.length > 1 && plot.times[0] < v[0] - kPlotWindow) {
        plot.times.shift();
        plot.values.forEach(function (a) { a.shift(); });
      }
      state.plotLast = Array.prototype.slice.call(v);
      ++state.plotSamples;
      plot.dirty = true;
    });
  }

  function drawPlot() {
    var canvas = document.getElementById('plot'), g = canvas.getContext('2d'), w = canvas.width, h = canvas.height;
    var end = info.mode === 'replay' ? replayTime : (plot.times.length ? plot.times[plot.times.length - 1] : 0);
    // the last kPlotWindow seconds, or all there is when that is less
    var start = Math.max(end - kPlotWindow, plot.times.length ? plot.times[0] : end);
    var span = end - start > 1e-9 ? end - start : 1, lo = Infinity, hi = -Infinity, first = -1, last = -1, k, i;
    for (k = 0; k < plot.times.length; ++k) {
      if (plot.times[k] < start || plot.times[k] > end) continue;
      if (first < 0) first = k;
      last = k;
      for (i = 0; i < plot.names.length; ++i) { lo = Math.min(lo, plot.values[i][k]); hi = Math.max(hi, plot.values[i][k]); }
    }
    g.fillStyle = '#1b1f24';
    g.fillRect(0, 0, w, h);
    var left = 56, top = 18, bottom = h - 18, right = w - 8;
    g.strokeStyle = '#555';
    g.strokeRect(left, top, right - left, bottom - top);
    g.font = '11px sans-serif';
    g.fillStyle = '#ccc';
    g.fillText('t = ' + start.toFixed(1) + ' .. ' + end.toFixed(1) + ' s', left, h - 4);
    state.plotEnd = end;
    if (first < 0) return;
    if (hi - lo < 1e-9) { hi += 0.5; lo -= 0.5; }
    g.fillText(hi.toPrecision(3), 2, top + 8);
    g.fillText(lo.toPrecision(3), 2, bottom);
    for (i = 0; i < plot.names.length; ++i) {
      g.strokeStyle = g.fillStyle = kPlotColours[i % kPlotColours.length];
      g.lineWidth = 2;
      g.beginPath();
      for (k = first; k <= last; ++k) {
        var x = left + (plot.times[k] - start) / span * (right - left);
        var y = bottom - (plot.values[i][k] - lo) / (hi - lo) * (bottom - top);
        if (k === first) g.moveTo(x, y); else g.lineTo(x, y);
      }
      g.stroke();
      g.fillText(plot.names[i], left + 4 + i * (right - left) / plot.names.length, 12);
    }
    ++state.plotDrawn;
  }

  function apply(buffer, offset) {
    var view = new DataView(buffer, offset, 16);
    state.time = view.getFloat64(0, true);
    state.seq = view.getFloat64(8, true);
    var p = new Float32Array(buffer, offset + 16, 7 * groups.length);
    for (var i = 0; i < groups.length; ++i) {
      groups[i].position.set(p[7 * i], p[7 * i + 1], p[7 * i + 2]);
      groups[i].quaternion.set(p[7 * i + 4], p[7 * i + 5], p[7 * i + 6], p[7 * i + 3]);
    }
    ++state.frames;
    document.getElementById('clock').textContent = 't = ' + state.time.toFixed(3) + ' s';
  }

  // replay: every frame of the run at once; the slider and the speed pick the time
  function startReplay() {
    document.getElementById('replay').style.display = 'inline';
    fetch('recording.bin').then(function (r) {
      if (!r.ok) throw new Error('recording.bin: HTTP ' + r.status);
      return r.arrayBuffer();
    }).then(function (buffer) {
      var size = 16 + 28 * groups.length, count = Math.floor(buffer.byteLength / size);
      if (count < 1) throw new Error('an empty recording');
      var times = [];
      for (var k = 0; k < count; ++k) times.push(new DataView(buffer, k * size, 8).getFloat64(0, true));
      recording = { buffer: buffer, size: size, times: times };
      var slider = document.getElementById('slider');
      slider.min = times[0];
      slider.max = times[count - 1];
      replayTime = times[0];
      slider.oninput = function () { replayTime = parseFloat(slider.value); showReplay(); };
      showReplay();
      state.replayFrames = count;
    }).catch(function (e) { fail('error: ' + e.message); });
  }

  function showReplay() {
    var t = recording.times, lo = 0, hi = t.length - 1;
    while (lo < hi) { var mid = (lo + hi + 1) >> 1; if (t[mid] <= replayTime) lo = mid; else hi = mid - 1; }
    apply(recording.buffer, lo * recording.size);
    document.getElementById('slider').value = replayTime;
    state.replayTime = replayTime;
    if (plot) plot.dirty = true;
  }

  // the replay goes on by `ms` of the page's clock times the speed chosen
  function advance(ms) {
    var speed = parseFloat(document.getElementById('speed').value);
    replayTime += speed * ms / 1000;
    var end = recording.times[recording.times.length - 1];
    if (replayTime > end) replayTime = recording.times[0];  // loop
    showReplay();
  }

  // clock=manual: the test's clock
  function tick(ms) {
    if (recording && !state.paused) advance(ms);
    return state.time;
  }

  function animate(wall) {
    requestAnimationFrame(animate);
    if (recording && !state.paused && !manualClock && lastWall) advance(wall - lastWall);
    lastWall = wall;
    // a paused replay still follows its slider; a paused live view holds its plot
    if (plot && plot.dirty && (!state.paused || recording)) { plot.dirty = false; drawPlot(); }
    if (latest && !state.paused) {
      apply(latest, 0);
      latest = null;
    }
    renderer.render(scene, camera);
  }
})();
