// A Foxglove WebSocket client (@foxglove/ws-protocol) against `vlab view --foxglove`:
//   node foxglove_client.mjs --foxglove PORT --http PORT --log RUN/log.csv --device pa10 --camera webcam
//        --allowed-origin ORIGIN [--messages N]
// Checks, each with a limit on the wait (no sleeps):
//   - a foreign Origin is refused (403) and the --allow-origin one is served;
//   - serverInfo: no capabilities (read-only); advertise: /tf, /scene, /DEVICE, /camera/CAMERA, each "cdr" with a
//     "ros2msg" schema that @foxglove/rosmsg parses;
//   - subscribed: N messages of /DEVICE, decoded by @foxglove/rosmsg2-serialization; one /tf naming every body
//     of the view's /scene.json (parent "world", unit quaternions); one /scene with an entity locked to each
//     body's frame, with primitives; one /camera/CAMERA whose bytes are a JPEG or PNG of the camera's size;
//   - a client advertise and a client message are answered with an error status, and messages keep coming;
//   - it prints "collected" (the caller may now end the run); once the run's log is in place (its folder appears
//     by a rename: watched, not polled), every decoded field equals, bit for bit, the log.csv column of the row at
//     the message's stamp.
// Exits 0 when all hold; otherwise prints what differs and exits 1.
import fs from "node:fs";
import path from "node:path";
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: its names through the default export
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;

const LIMIT_MS = 20000; // a guard against a hang, not a timing check

const args = {};
for (let i = 2; i + 1 < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, "")] = process.argv[i + 1];
const url = `ws://127.0.0.1:${args.foxglove}/`;
const wanted = Number(args.messages ?? 10);

function fail(message) {
  console.log(`foxglove_client: FAIL: ${message}`);
  process.exit(1);
}

// resolves when `test(value)` is true for an event of `emitter`'s `name`, within the limit
function within(what, start) {
  return new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no ${what} within ${LIMIT_MS} ms`)), LIMIT_MS);
    start((value) => {
      clearTimeout(timer);
      resolve(value);
    }, (error) => {
      clearTimeout(timer);
      reject(error);
    });
  });
}

// the HTTP status of a refused upgrade, or "open" when it was accepted
function upgradeWith(origin) {
  return within(`answer to an upgrade from ${origin}`, (resolve) => {
    const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL], { headers: { Origin: origin } });
    ws.on("unexpected-response", (_req, res) => resolve(res.statusCode));
    ws.on("open", () => {
      ws.close();
      resolve("open");
    });
    ws.on("error", () => {});
  });
}

// JPEG: the first SOFn segment's height and width; PNG: the IHDR's
function imageSize(bytes) {
  if (bytes[0] === 0x89 && bytes[1] === 0x50 && bytes[2] === 0x4e && bytes[3] === 0x47) {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    return { format: "png", width: view.getUint32(16), height: view.getUint32(20) };
  }
  if (bytes[0] !== 0xff || bytes[1] !== 0xd8 || bytes[2] !== 0xff) return undefined;
  for (let i = 2; i + 9 < bytes.length; ) {
    if (bytes[i] !== 0xff) return undefined;
    const marker = bytes[i + 1];
    const length = (bytes[i + 2] << 8) | bytes[i + 3];
    if (marker >= 0xc0 && marker <= 0xcf && marker !== 0xc4 && marker !== 0xc8 && marker !== 0xcc) {
      return { format: "jpeg", height: (bytes[i + 5] << 8) | bytes[i + 6], width: (bytes[i + 7] << 8) | bytes[i + 8] };
    }
    i += 2 + length;
  }
  return undefined;
}

// a log column's part after its device as a ROS 2 field name ("q.S1" -> "q_s1"), as scene_messages.h says
function fieldName(part) {
  let name = part.toLowerCase().replace(/[^a-z0-9]+/g, "_").replace(/^_+|_+$/g, "");
  if (/^[0-9]/.test(name)) name = "f" + name;
  return name || "value";
}

// waits until `file` exists: its folder is renamed into place when the run ends
function fileAppears(file) {
  const parent = path.dirname(path.dirname(file));
  return within(`${file}`, (resolve) => {
    const watcher = fs.watch(parent, () => {
      if (fs.existsSync(file)) {
        watcher.close();
        resolve();
      }
    });
    if (fs.existsSync(file)) {
      watcher.close();
      resolve();
    }
  });
}

function bits(x) {
  const view = new DataView(new ArrayBuffer(8));
  view.setFloat64(0, x, true);
  return view.getBigUint64(0, true).toString(16);
}

async function main() {
  // who may connect: a foreign page no, the allowed web app yes
  const foreign = await upgradeWith("http://evil.example");
  if (foreign !== 403) fail(`an upgrade with Origin http://evil.example got ${foreign}, expected 403`);
  const allowed = await upgradeWith(args["allowed-origin"]);
  if (allowed !== "open") fail(`an upgrade with Origin ${args["allowed-origin"]} got ${allowed}, expected served`);

  const scene = await (await fetch(`http://127.0.0.1:${args.http}/scene.json`)).json();
  const bodies = scene.bodies.map((name, i) => (name && name !== "world" ? name : `body_${i}`)); // all distinct here
  const deviceTopic = `/${args.device}`, cameraTopic = `/camera/${args.camera}`;

  const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
  const readers = new Map(); // channel id -> {topic, reader}
  const bySubscription = new Map();
  const deviceMessages = [];
  let tf, sceneUpdate, image, statuses = [], afterRefusals = 0, refusalsSent = false;
  const done = within("serverInfo, advertise, messages and status answers", (resolve, reject) => {
    client.on("error", (e) => reject(e));
    client.on("close", () => reject(new Error("the server closed the connection")));
    client.on("serverInfo", (info) => {
      if (info.name !== "vlab view") reject(new Error(`serverInfo name ${info.name}`));
      if (info.capabilities.length !== 0) reject(new Error(`capabilities ${JSON.stringify(info.capabilities)}`));
    });
    client.on("advertise", (channels) => {
      for (const c of channels) {
        if (c.encoding !== "cdr" || c.schemaEncoding !== "ros2msg") {
          reject(new Error(`${c.topic}: encoding ${c.encoding}, schema encoding ${c.schemaEncoding}`));
        }
        const definitions = parse(c.schema, { ros2: true });
        if (definitions.length === 0 || definitions[0].definitions.length === 0) {
          reject(new Error(`${c.topic}: schema ${c.schemaName} parses to no fields`));
        }
        readers.set(c.id, { topic: c.topic, reader: new MessageReader(definitions) });
      }
      const topics = [...readers.values()].map((r) => r.topic);
      for (const t of ["/tf", "/scene", deviceTopic, cameraTopic]) {
        if (!topics.includes(t)) reject(new Error(`no channel ${t} among ${topics.join(", ")}`));
      }
      for (const id of readers.keys()) bySubscription.set(client.subscribe(id), id);
      // a read-only server: publishing is refused
      client.advertise({ topic: "/pa10/command", encoding: "cdr", schemaName: "std_msgs/msg/Float64" });
      client.sendMessage(0, new Uint8Array([0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]));
      refusalsSent = true;
    });
    client.on("status", (s) => statuses.push(s));
    client.on("message", ({ subscriptionId, data }) => {
      const { topic, reader } = readers.get(bySubscription.get(subscriptionId));
      const message = reader.readMessage(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
      if (refusalsSent && statuses.length >= 2) ++afterRefusals;
      if (topic === deviceTopic && deviceMessages.length < wanted) deviceMessages.push(message);
      if (topic === "/tf") tf = message;
      if (topic === "/scene") sceneUpdate = message;
      if (topic === cameraTopic && !image) image = message;
      if (deviceMessages.length >= wanted && tf && sceneUpdate && image && afterRefusals >= 3) resolve();
    });
  });
  await done.catch((e) => fail(e.message));
  client.close();

  // read-only: both refusals answered with an error status naming it
  if (statuses.length !== 2 || !statuses.every((s) => s.level === 2 && /read-only/.test(s.message))) {
    fail(`expected 2 read-only error statuses, got ${JSON.stringify(statuses)}`);
  }
  // /tf: every body, from the world, unit quaternions
  const children = tf.transforms.map((t) => t.child_frame_id);
  if (JSON.stringify(children) !== JSON.stringify(bodies)) {
    fail(`/tf names ${children.join(",")}, the scene's bodies are ${bodies.join(",")}`);
  }
  for (const t of tf.transforms) {
    const q = t.transform.rotation;
    if (t.header.frame_id !== "world") fail(`/tf ${t.child_frame_id}: parent ${t.header.frame_id}`);
    if (Math.abs(Math.hypot(q.x, q.y, q.z, q.w) - 1) > 1e-9) fail(`/tf ${t.child_frame_id}: |q| != 1`);
  }
  // /scene: an entity locked to each body's frame (and the world's), with primitives
  const entities = sceneUpdate.entities.filter((e) => e.frame_id !== "world");
  if (JSON.stringify(entities.map((e) => e.frame_id)) !== JSON.stringify(bodies)) {
    fail(`/scene entities ${entities.map((e) => e.frame_id).join(",")}, the scene's bodies are ${bodies.join(",")}`);
  }
  const primitives = (e) =>
    e.cubes.length + e.spheres.length + e.cylinders.length + e.triangles.length + e.lines.length + e.arrows.length;
  for (const e of entities) {
    if (!e.frame_locked || primitives(e) === 0) fail(`/scene entity ${e.frame_id}: not locked, or no primitives`);
  }
  // the camera's picture: its signature and the camera's size
  const size = imageSize(image.data);
  if (!size || size.format !== image.format) fail(`${cameraTopic}: format ${image.format}, bytes ${size?.format}`);
  if (size.width !== Number(args.width) || size.height !== Number(args.height)) {
    fail(`${cameraTopic}: ${size.width} x ${size.height}, expected ${args.width} x ${args.height}`);
  }
  if (image.header.frame_id !== args.camera) fail(`${cameraTopic}: frame_id ${image.header.frame_id}`);

  // the device's messages against the log, bit for bit, at the same stamps, once the run has ended
  console.log(`foxglove_client: collected ${deviceMessages.length} ${deviceTopic} messages, /tf, /scene, ${cameraTopic}`);
  await fileAppears(args.log).catch((e) => fail(e.message));
  const lines = fs.readFileSync(args.log, "utf8").trim().split("\n");
  const columns = lines[0].split(",");
  const rows = lines.slice(1).map((l) => l.split(","));
  const time = columns.indexOf("time");
  const fields = columns
    .map((c, i) => ({ column: i, name: c }))
    .filter((c) => c.name.startsWith(args.device + "."))
    .map((c) => ({ ...c, field: fieldName(c.name.slice(args.device.length + 1)) }));
  let compared = 0;
  for (const m of deviceMessages) {
    const t = m.stamp.sec + (m.stamp.nanosec ?? m.stamp.nsec) * 1e-9; // the decoder names it nsec
    const row = rows.find((r) => Math.abs(Number(r[time]) - t) < 0.5e-3); // periods are 2 ms apart
    if (!row) fail(`no log row at t = ${t}`);
    for (const f of fields) {
      if (!(f.field in m)) continue; // a column the scene device does not send
      const logged = Number(row[f.column]);
      if (bits(logged) !== bits(m[f.field])) fail(`${f.name} at t = ${t}: log ${row[f.column]}, stream ${m[f.field]}`);
      ++compared;
    }
  }
  const sent = fields.filter((f) => f.field in deviceMessages[0]).length;
  if (sent === 0) fail(`no field of ${deviceTopic} is a log column`);
  console.log(
    `foxglove_client: ${deviceMessages.length} ${deviceTopic} messages (${sent} fields each, ${compared} values ` +
      `equal to the log), /tf of ${children.length} bodies, /scene of ${sceneUpdate.entities.length} entities, ` +
      `${cameraTopic} ${size.format} ${size.width}x${size.height}`
  );
  process.exit(0);
}

main().catch((e) => fail(e.stack ?? e.message));
