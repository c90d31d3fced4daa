// Reads a run folder's log.mcap with the MCAP reference reader (@mcap/core: the
// streaming reader over the whole file, and the indexed reader through its
// summary, chunk and message indexes) and checks it against the run's other files:
//   - both readers read every record (CRCs checked) and yield the same messages
//   - every schema parses as ros2msg (@foxglove/rosmsg) and every message decodes
//     with its schema (@foxglove/rosmsg2-serialization), all its bytes consumed
//   - each device channel /DEVICE holds one message per row of log.csv, stamped
//     with the row's time, and each field (named in the schema's comment after it)
//     equals the column's value bit for bit (JS parses the shortest round-trip
//     decimal exactly)
//   - /scene holds one SceneUpdate at t = 0: an entity per body of scene.json with
//     a geom, locked to its frame, a primitive per geom (a capsule: three);
//   - /tf holds one message per frame of poses.bin, the bodies of scene.json as
//     child frames of "world", each value poses.bin's float32 (none without poses.bin)
//   - each /camera/NAME message is CAMERA/rgb_NNNNNN.png byte for byte, a PNG of
//     the size summary.json gives the camera, at the time frames.csv gives
// Exits 0 when all hold, else prints the first difference and exits 1.
//   node read_mcap.mjs RUN_DIR
import fs from "node:fs";
import path from "node:path";

import { CdrReader } from "@foxglove/cdr";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";

const dir = process.argv[2];
function fail(why) {
  console.error(`read_mcap: ${dir}/log.mcap: ${why}`);
  process.exit(1);
}
function check(ok, why) {
  if (!ok) fail(why());
}

const bytes = new Uint8Array(fs.readFileSync(path.join(dir, "log.mcap")));
const decompressHandlers = { zstd: (data, size) => decompress(data, new Uint8Array(Number(size))) };

// the streaming reader: every record in file order
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const streamed = [];
const streamSchemas = new Map();
const streamChannels = new Map();
let header, footer;
for (let record; (record = stream.nextRecord()); ) {
  if (record.type === "Header") header = record;
  if (record.type === "Footer") footer = record;
  if (record.type === "Schema") streamSchemas.set(record.id, record);
  if (record.type === "Channel") streamChannels.set(record.id, record);
  if (record.type === "Message") streamed.push(record);
}
check(stream.done(), () => "the streaming reader did not reach the end (cut short?)");
check(header && header.library === "vlab", () => `header library ${header?.library}`);
check(footer, () => "no footer");

// the indexed reader: the summary, then messages through the chunk and message indexes
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const messages = [];
for await (const m of indexed.readMessages({ validateCrcs: true })) messages.push(m);
check(indexed.statistics, () => "no statistics in the summary");
check(
  indexed.statistics.messageCount === BigInt(messages.length),
  () => `statistics: ${indexed.statistics.messageCount} messages, the indexed reader read ${messages.length}`,
);
check(messages.length === streamed.length, () => `indexed ${messages.length} messages, streamed ${streamed.length}`);
const key = (m) => `${m.logTime}/${m.channelId}/${m.sequence}`;
const byKey = new Map(streamed.map((m) => [key(m), m]));
for (const m of messages) {
  const s = byKey.get(key(m));
  check(s && Buffer.compare(Buffer.from(s.data), Buffer.from(m.data)) === 0, () => `message ${key(m)} differs`);
}
for (let i = 1; i < messages.length; ++i) {
  check(messages[i - 1].logTime <= messages[i].logTime, () => `indexed reader out of time order at ${i}`);
}

// every schema parsed, every message decoded whole
const readers = new Map();
for (const [id, channel] of indexed.channelsById) {
  const schema = indexed.schemasById.get(channel.schemaId);
  check(schema && schema.encoding === "ros2msg", () => `channel ${channel.topic}: schema ${channel.schemaId}`);
  check(channel.messageEncoding === "cdr", () => `channel ${channel.topic}: encoding ${channel.messageEncoding}`);
  const stored = streamSchemas.get(schema.id);
  check(stored && stored.name === schema.name, () => `schema ${schema.name} not in the data section`);
  check(streamChannels.get(id)?.topic === channel.topic, () => `channel ${channel.topic} not in the data section`);
  const text = new TextDecoder().decode(schema.data);
  let definitions;
  try {
    definitions = parse(text, { ros2: true });
  } catch (e) {
    fail(`schema ${schema.name}: ${e.message}`);
  }
  readers.set(id, { channel, schema, text, reader: new MessageReader(definitions) });
}
const decoded = new Map();  // channel id -> [{time, msg, data}]
for (const m of messages) {
  const r = readers.get(m.channelId);
  check(r, () => `message on unknown channel ${m.channelId}`);
  const cdr = new CdrReader(m.data);
  let msg;
  try {
    msg = r.reader.readComplexType(r.reader.rootDefinition, cdr);
  } catch (e) {
    fail(`${r.channel.topic} message at ${m.logTime}: ${e.message}`);
  }
  check(
    cdr.decodedBytes === m.data.byteLength,
    () => `${r.channel.topic} at ${m.logTime}: ${cdr.decodedBytes} of ${m.data.byteLength} bytes decoded`,
  );
  check(m.publishTime === m.logTime, () => `${r.channel.topic}: publish time differs from log time`);
  if (!decoded.has(m.channelId)) decoded.set(m.channelId, []);
  decoded.get(m.channelId).push({ time: m.logTime, msg, data: m.data });
}
const topic = (name) => [...readers.values()].find((r) => r.channel.topic === name);
// (the decoder names builtin_interfaces/Time's nanosec "nsec", as rostime does)
const stampNs = (s) => BigInt(s.sec) * 1000000000n + BigInt(s.nanosec ?? s.nsec);
const ns = (t) => BigInt(Math.round(t * 1e9));

// the signals against log.csv, bit for bit
const lines = fs.readFileSync(path.join(dir, "log.csv"), "utf8").trimEnd().split("\n");
const columns = lines[0].split(",");
const rows = lines.slice(1).map((l) => l.split(",").map(Number.parseFloat));
const timeColumn = columns.indexOf("time");
let signalChannels = 0;
for (const [id, r] of readers) {
  if (!r.schema.name.startsWith("vlab_msgs/msg/")) continue;
  ++signalChannels;
  // "float64 FIELD  # COLUMN": the column each field carries
  const fields = [...r.text.split("=".repeat(80))[0].matchAll(/^float64 (\w+)\s+# (\S+)$/gm)].map((f) => ({
    field: f[1],
    column: columns.indexOf(f[2]),
    name: f[2],
  }));
  check(fields.length > 0, () => `${r.channel.topic}: no fields`);
  for (const f of fields) check(f.column >= 0, () => `${r.channel.topic}: field ${f.field}: no column ${f.name}`);
  const got = decoded.get(id) ?? [];
  check(got.length === rows.length, () => `${r.channel.topic}: ${got.length} messages, log.csv ${rows.length} rows`);
  got.forEach(({ time, msg }, i) => {
    const t = rows[i][timeColumn];
    check(time === ns(t) && stampNs(msg.stamp) === ns(t), () => `${r.channel.topic} row ${i}: time ${time}, not ${t}`);
    for (const f of fields) {
      const want = rows[i][f.column];
      check(Object.is(msg[f.field], want), () => `${r.channel.topic} row ${i} ${f.name}: ${msg[f.field]}, not ${want}`);
    }
  });
}
check(signalChannels > 0, () => "no device channels");
const signalColumns = [...readers.values()]
  .filter((r) => r.schema.name.startsWith("vlab_msgs/msg/"))
  .reduce((n, r) => n + (r.text.split("=".repeat(80))[0].match(/^float64 /gm) ?? []).length, 0);
check(signalColumns === columns.length - 1, () => `${signalColumns} fields for ${columns.length - 1} columns`);

// /tf against poses.bin and scene.json
const tf = topic("/tf");
const posesFile = path.join(dir, "poses.bin");
let tfCount = 0;
if (fs.existsSync(posesFile)) {
  check(tf, () => "poses.bin, but no /tf");
  const sceneJson = JSON.parse(fs.readFileSync(path.join(dir, "scene.json"), "utf8"));
  const bodies = sceneJson.bodies;
  // the frames of /tf and /scene: a body's name, or body_N when it has none, or its name is taken or "world"
  const frameNames = [];
  bodies.forEach((b, i) => frameNames.push(b === "" || b === "world" || frameNames.includes(b) ? `body_${i}` : b));
  // /scene: one SceneUpdate at t = 0, an entity per body with a geom (locked to its frame) and the world's
  const scene = topic("/scene");
  check(scene && scene.schema.name === "foxglove_msgs/msg/SceneUpdate", () => "poses.bin, but no /scene");
  const updates = decoded.get(scene.channel.id) ?? [];
  check(updates.length === 1 && updates[0].time === 0n, () => `/scene: ${updates.length} messages, not one at t = 0`);
  const entities = updates[0].msg.entities;
  const primitives = { box: 1, sphere: 1, ellipsoid: 1, cylinder: 1, plane: 1, capsule: 3 };  // meshes: none (no model)
  const withGeoms = new Set(sceneJson.geoms.filter((g) => primitives[g.type]).map((g) => g.body));
  const geomsOf = (e) => e.cubes.length + e.spheres.length + e.cylinders.length + e.triangles.length;
  check(entities.length === withGeoms.size, () => `/scene: ${entities.length} entities for ${withGeoms.size} bodies`);
  for (const e of entities) {
    const b = e.frame_id === "world" ? -1 : frameNames.indexOf(e.frame_id);
    check(e.id === e.frame_id && e.frame_locked && withGeoms.has(b), () => `/scene: entity ${e.id}`);
    const drawn = sceneJson.geoms.filter((g) => g.body === b).reduce((n, g) => n + (primitives[g.type] ?? 0), 0);
    check(geomsOf(e) === drawn, () => `/scene ${e.id}: ${geomsOf(e)} primitives for ${drawn} geoms`);
  }
  const poses = fs.readFileSync(posesFile);
  const frameSize = 16 + 28 * bodies.length;
  const frames = poses.length / frameSize;
  const got = decoded.get(tf.channel.id);
  check(got.length === frames, () => `/tf: ${got.length} messages, poses.bin ${frames} frames`);
  got.forEach(({ time, msg }, i) => {
    const at = i * frameSize;
    const t = poses.readDoubleLE(at);
    check(time === ns(t), () => `/tf message ${i}: time ${time}, poses.bin ${t}`);
    check(msg.transforms.length === bodies.length, () => `/tf message ${i}: ${msg.transforms.length} transforms`);
    msg.transforms.forEach((x, b) => {
      const name = frameNames[b];
      check(x.header.frame_id === "world" && x.child_frame_id === name, () => `/tf ${i}: frame ${x.child_frame_id}`);
      check(stampNs(x.header.stamp) === ns(t), () => `/tf ${i} ${name}: stamp`);
      const v = [x.transform.translation.x, x.transform.translation.y, x.transform.translation.z,
        x.transform.rotation.w, x.transform.rotation.x, x.transform.rotation.y, x.transform.rotation.z];
      v.forEach((value, k) => {
        const want = poses.readFloatLE(at + 16 + 28 * b + 4 * k);
        check(Object.is(value, want), () => `/tf ${i} ${name} value ${k}: ${value}, poses.bin ${want}`);
      });
    });
  });
  tfCount = got.length;
} else {
  check(!tf && !topic("/scene"), () => "/tf or /scene without poses.bin");
}

// the cameras against their PNG files, frames.csv and summary.json
const summary = JSON.parse(fs.readFileSync(path.join(dir, "summary.json"), "utf8"));
const outputs = (summary.images?.outputs ?? []).filter((o) => o.files.some((f) => f.endsWith("/rgb_NNNNNN.png")));
let images = 0;
for (const o of outputs) {
  const r = topic(`/camera/${o.camera}`);
  check(r && r.schema.name === "sensor_msgs/msg/CompressedImage", () => `no /camera/${o.camera}`);
  const times = fs.readFileSync(path.join(dir, o.camera, "frames.csv"), "utf8").trimEnd().split("\n").slice(1);
  const got = decoded.get(r.channel.id) ?? [];
  check(got.length === times.length && got.length === o.frames, () => `/camera/${o.camera}: ${got.length} frames`);
  got.forEach(({ time, msg }, n) => {
    const t = Number.parseFloat(times[n].split(",")[1]);
    check(time === ns(t), () => `/camera/${o.camera} frame ${n}: time ${time}, frames.csv ${t}`);
    check(msg.format === "png" && msg.header.frame_id === o.camera, () => `/camera/${o.camera} ${n}: format`);
    const data = Buffer.from(msg.data);
    const file = fs.readFileSync(path.join(dir, o.camera, `rgb_${String(n).padStart(6, "0")}.png`));
    check(Buffer.compare(data, file) === 0, () => `/camera/${o.camera} frame ${n}: not the bytes of its PNG`);
    check(data.subarray(0, 8).equals(Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a])), () => "not a PNG");
    const w = data.readUInt32BE(16), h = data.readUInt32BE(20);  // IHDR
    check(w === o.width && h === o.height, () => `/camera/${o.camera} ${n}: ${w}x${h}, not ${o.width}x${o.height}`);
  });
  images += got.length;
}
check(
  readers.size === signalChannels + (tf ? 2 : 0) + outputs.length,
  () => `${readers.size} channels, expected ${signalChannels} devices, /scene, /tf and ${outputs.length} cameras`,
);
console.log(
  `read_mcap: ${dir}/log.mcap: ${messages.length} messages (${rows.length} rows on ${signalChannels} devices, ` +
    `${tfCount} /tf, ${images} images), ${indexed.chunkIndexes.length} chunks: all checks hold`,
);
