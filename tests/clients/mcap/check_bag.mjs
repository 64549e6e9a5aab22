#!/usr/bin/env node
// Checks a rosbag2 folder written by skytrace with the libraries Foxglove's viewer reads bags with:
// @mcap/core (indexed reader and stream reader, CRCs checked), @mcap/support's decompressors,
// @foxglove/rosmsg (ros2msg schemas) and @foxglove/rosmsg2-serialization (CDR).
//
//   node check_bag.mjs BAG_FOLDER [--expect FILE.json] [--values]
//
// Every message is decoded with MessageReader and encoded again with MessageWriter; the bytes must
// be equal. metadata.yaml must agree with the MCAP file (counts, times, topics, QoS). Prints one
// JSON object: {"ok": true|false, "errors": [...], "topics": [...], ...}; with --values it also
// holds every decoded message ("values": {topic: [message, ...]}). Exit status 0 when ok, 1 when a
// check failed, 2 on bad usage.
//
// --expect FILE.json: {"topics": {"/fix": {"type": "sensor_msgs/msg/NavSatFix", "count": 3}},
//                      "messages": {"/fix": [{"latitude": 52.5}, ...]}}
// "topics" must list exactly the bag's topics; each object of "messages" must be contained in the
// decoded message of the same index (numbers equal, arrays element by element).

import { open, readFile, stat } from "node:fs/promises";
import path from "node:path";
import { crc32Final, crc32Init, crc32Update } from "@foxglove/crc";
import { parse as parseMessageDefinition } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import YAML from "yaml";

const errors = [];
const fail = (message) => errors.push(message);

function usage() {
  process.stderr.write("usage: node check_bag.mjs BAG_FOLDER [--expect FILE.json] [--values]\n");
  process.exit(2);
}

const args = process.argv.slice(2);
let bagFolder;
let expectFile;
let printValues = false;
for (let i = 0; i < args.length; i++) {
  if (args[i] === "--expect") {
    expectFile = args[++i];
    if (expectFile === undefined) usage();
  } else if (args[i] === "--values") {
    printValues = true;
  } else if (bagFolder === undefined && !args[i].startsWith("--")) {
    bagFolder = args[i];
  } else {
    usage();
  }
}
if (bagFolder === undefined) usage();

// JSON cannot hold bigint or typed arrays: int64 values that fit become numbers.
function toPlain(value) {
  if (typeof value === "bigint") {
    return value >= BigInt(Number.MIN_SAFE_INTEGER) && value <= BigInt(Number.MAX_SAFE_INTEGER)
      ? Number(value)
      : value.toString();
  }
  if (ArrayBuffer.isView(value)) return Array.from(value, toPlain);
  if (Array.isArray(value)) return value.map(toPlain);
  if (value !== null && typeof value === "object") {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, toPlain(v)]));
  }
  return value;
}

// Whether `expected` (from JSON) is contained in `actual` (decoded); mismatches go to `where`.
function contains(actual, expected, where, mismatches) {
  if (expected === null || typeof expected !== "object") {
    let equal;
    if (typeof actual === "bigint") {
      equal = typeof expected === "number" || typeof expected === "string" ? actual === BigInt(expected) : false;
    } else {
      equal = actual === expected;
    }
    if (!equal) mismatches.push(`${where}: ${JSON.stringify(toPlain(actual))} != ${JSON.stringify(expected)}`);
    return;
  }
  if (Array.isArray(expected)) {
    const list = ArrayBuffer.isView(actual) || Array.isArray(actual) ? Array.from(actual) : undefined;
    if (list === undefined || list.length !== expected.length) {
      mismatches.push(`${where}: length ${list?.length} != ${expected.length}`);
      return;
    }
    expected.forEach((item, i) => contains(list[i], item, `${where}[${i}]`, mismatches));
    return;
  }
  if (actual === null || typeof actual !== "object") {
    mismatches.push(`${where}: not an object`);
    return;
  }
  for (const [key, item] of Object.entries(expected)) {
    if (!(key in actual)) {
      mismatches.push(`${where}.${key}: missing`);
      continue;
    }
    contains(actual[key], item, `${where}.${key}`, mismatches);
  }
}

function sameBytes(a, b) {
  return a.byteLength === b.byteLength && Buffer.compare(Buffer.from(a.buffer, a.byteOffset, a.byteLength),
    Buffer.from(b.buffer, b.byteOffset, b.byteLength)) === 0;
}

async function check() {
  const expected = expectFile === undefined ? undefined : JSON.parse(await readFile(expectFile, "utf8"));
  // Decoded messages are kept only as far as --values or the expectations need them.
  const keep = (topicName, index) => printValues || index < (expected?.messages?.[topicName]?.length ?? 0);
  // --- metadata.yaml -------------------------------------------------------------------------------
  const metadataText = await readFile(path.join(bagFolder, "metadata.yaml"), "utf8");
  const info = YAML.parse(metadataText, { intAsBigInt: true })?.rosbag2_bagfile_information;
  if (info === undefined) throw new Error("metadata.yaml: no rosbag2_bagfile_information");
  if (info.storage_identifier !== "mcap") fail(`metadata.yaml: storage_identifier ${info.storage_identifier}`);
  if (info.relative_file_paths?.length !== 1) fail("metadata.yaml: expected one relative file path");
  const mcapName = info.relative_file_paths?.[0] ?? "";
  if (info.files?.length !== 1 || info.files[0].path !== mcapName) fail("metadata.yaml: files[0] does not name the MCAP file");
  const mcapPath = path.join(bagFolder, mcapName);

  // --- the MCAP file through the indexed reader (what Foxglove does for a local file) --------------
  const decompressHandlers = await loadDecompressHandlers();
  const fileHandle = await open(mcapPath, "r");
  const fileSize = BigInt((await stat(mcapPath)).size);
  const readable = {
    size: async () => fileSize,
    read: async (offset, length) => {
      const buffer = new Uint8Array(Number(length));
      const { bytesRead } = await fileHandle.read(buffer, 0, buffer.length, Number(offset));
      if (bytesRead !== buffer.length) throw new Error(`short read at ${offset}`);
      return buffer;
    },
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  if (reader.header.profile !== "ros2") fail(`header profile '${reader.header.profile}' is not ros2`);
  const stats = reader.statistics;
  if (stats === undefined) fail("no Statistics record in the summary");

  // Schemas parsed once; one reader and writer per schema.
  const codecs = new Map();
  for (const [id, schema] of reader.schemasById) {
    if (schema.encoding !== "ros2msg") fail(`schema ${schema.name}: encoding ${schema.encoding}`);
    try {
      const definitions = parseMessageDefinition(new TextDecoder().decode(schema.data), { ros2: true });
      codecs.set(id, { reader: new MessageReader(definitions), writer: new MessageWriter(definitions) });
    } catch (error) {
      fail(`schema ${schema.name}: ${error.message}`);
    }
  }

  const topics = new Map();  // channel id -> summary
  for (const [id, channel] of reader.channelsById) {
    if (channel.messageEncoding !== "cdr") fail(`${channel.topic}: message encoding ${channel.messageEncoding}`);
    const schema = reader.schemasById.get(channel.schemaId);
    if (schema === undefined) fail(`${channel.topic}: unknown schema ${channel.schemaId}`);
    let qos;
    try {
      qos = YAML.parse(channel.metadata.get("offered_qos_profiles") ?? "");
    } catch (error) {
      fail(`${channel.topic}: offered_qos_profiles is not YAML (${error.message})`);
    }
    if (!Array.isArray(qos) || qos.length === 0) fail(`${channel.topic}: offered_qos_profiles is not a list of profiles`);
    if (!channel.metadata.has("topic_type_hash")) fail(`${channel.topic}: no topic_type_hash metadata`);
    topics.set(id, { name: channel.topic, type: schema?.name, count: 0, qos: qos?.[0], decoded: [] });
  }

  let messageCount = 0;
  let previousLogTime = -1n;
  let reencodeFailures = 0;
  for await (const message of reader.readMessages({ validateCrcs: true })) {
    messageCount++;
    const topic = topics.get(message.channelId);
    if (topic === undefined) {
      fail(`message on unknown channel ${message.channelId}`);
      continue;
    }
    topic.count++;
    if (message.logTime < previousLogTime) fail(`${topic.name}: messages out of log time order`);
    previousLogTime = message.logTime;
    if (message.publishTime !== message.logTime) fail(`${topic.name}: publish time differs from log time`);
    const codec = codecs.get(reader.channelsById.get(message.channelId).schemaId);
    if (codec === undefined) continue;
    let decoded;
    try {
      decoded = codec.reader.readMessage(message.data);
    } catch (error) {
      fail(`${topic.name} message ${topic.count - 1}: cannot decode (${error.message})`);
      continue;
    }
    if (codec.reader.lastReadHadTrailingBytes()) fail(`${topic.name} message ${topic.count - 1}: trailing bytes`);
    const encoded = codec.writer.writeMessage(decoded);
    if (!sameBytes(encoded, message.data) && reencodeFailures++ < 5) {
      fail(`${topic.name} message ${topic.count - 1}: MessageWriter gives ${encoded.byteLength} bytes that differ ` +
        `from the bag's ${message.data.byteLength}`);
    }
    if (keep(topic.name, topic.count - 1)) topic.decoded.push(decoded);
  }

  // --- the same file read front to back (what a streaming reader or `ros2 bag play` sees) -----------
  // In pieces, so that a long bag is not held in memory; the data section's CRC on the way (it runs
  // from the leading magic to Data End, the 13 bytes just before the summary).
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  const dataEndOffset = reader.footer.summaryStart === 0n ? undefined : Number(reader.footer.summaryStart) - 13;
  let dataCrc = crc32Init();
  let streamMessages = 0;
  let dataEnd;
  let footer;
  const opcodesSeen = [];
  const seenChannels = new Set();
  const piece = new Uint8Array(4 << 20);
  for (let offset = 0; offset < Number(fileSize);) {
    const { bytesRead } = await fileHandle.read(piece, 0, piece.length, offset);
    if (bytesRead === 0) throw new Error(`short read at ${offset}`);
    const bytes = piece.subarray(0, bytesRead);
    if (dataEndOffset !== undefined && offset < dataEndOffset) {
      dataCrc = crc32Update(dataCrc, bytes.subarray(0, Math.min(bytesRead, dataEndOffset - offset)));
    }
    offset += bytesRead;
    stream.append(bytes);
    for (let record; (record = stream.nextRecord()) !== undefined;) {
      opcodesSeen.push(record.type);
      if (record.type === "Channel") seenChannels.add(record.id);
      if (record.type === "Message") {
        streamMessages++;
        if (!seenChannels.has(record.channelId)) fail(`message on channel ${record.channelId} before its Channel record`);
      }
      if (record.type === "DataEnd") dataEnd = record;
      if (record.type === "Footer") footer = record;
    }
  }
  if (!stream.done()) fail("stream reader: file did not end with the footer and magic");
  if (opcodesSeen[0] !== "Header") fail("stream reader: first record is not the Header");
  if (streamMessages !== messageCount) fail(`stream reader found ${streamMessages} messages, indexed reader ${messageCount}`);
  if (dataEnd === undefined || footer === undefined || dataEndOffset === undefined) {
    fail("no Data End, Footer or summary");
  } else if (dataEnd.dataSectionCrc !== 0) {
    const crc = crc32Final(dataCrc);
    if (crc !== dataEnd.dataSectionCrc) fail(`data section CRC ${crc} != ${dataEnd.dataSectionCrc}`);
  }
  const chunkCount = reader.chunkIndexes.length;
  const compression = [...new Set(reader.chunkIndexes.map((c) => c.compression))];

  // --- metadata.yaml against the MCAP file ----------------------------------------------------------
  if (stats !== undefined) {
    if (stats.messageCount !== BigInt(messageCount)) fail(`Statistics message_count ${stats.messageCount} != ${messageCount}`);
    if (stats.chunkCount !== chunkCount) fail(`Statistics chunk_count ${stats.chunkCount} != ${chunkCount} chunk indexes`);
    for (const [id, topic] of topics) {
      const counted = stats.channelMessageCounts.get(id) ?? 0n;
      if (counted !== BigInt(topic.count)) fail(`${topic.name}: Statistics count ${counted} != ${topic.count}`);
    }
    if (info.message_count !== BigInt(messageCount)) fail(`metadata.yaml message_count ${info.message_count} != ${messageCount}`);
    if (info.files?.[0]?.message_count !== BigInt(messageCount)) fail("metadata.yaml files[0].message_count differs");
    if (messageCount > 0) {
      const start = info.starting_time?.nanoseconds_since_epoch;
      const duration = info.duration?.nanoseconds;
      if (start !== stats.messageStartTime) fail(`metadata.yaml starting_time ${start} != ${stats.messageStartTime}`);
      if (duration !== stats.messageEndTime - stats.messageStartTime) fail(`metadata.yaml duration ${duration} differs`);
    }
  }
  const bagTopics = info.topics_with_message_count ?? [];
  if (bagTopics.length !== topics.size) fail(`metadata.yaml lists ${bagTopics.length} topics, the MCAP file ${topics.size}`);
  for (const entry of bagTopics) {
    const meta = entry.topic_metadata ?? {};
    const topic = [...topics.values()].find((t) => t.name === meta.name);
    if (topic === undefined) {
      fail(`metadata.yaml topic ${meta.name} is not in the MCAP file`);
      continue;
    }
    if (meta.type !== topic.type) fail(`${meta.name}: metadata.yaml type ${meta.type} != schema ${topic.type}`);
    if (meta.serialization_format !== "cdr") fail(`${meta.name}: serialization_format ${meta.serialization_format}`);
    if (entry.message_count !== BigInt(topic.count)) fail(`${meta.name}: metadata.yaml count ${entry.message_count} != ${topic.count}`);
    if (JSON.stringify(toPlain(meta.offered_qos_profiles?.[0])) !== JSON.stringify(topic.qos)) {
      fail(`${meta.name}: metadata.yaml QoS differs from the channel's offered_qos_profiles`);
    }
  }
  // rosbag2 keeps the bag metadata in the MCAP file too ("rosbag2" Metadata record).
  const records = [];
  for await (const record of reader.readMetadata({ name: "rosbag2" })) records.push(record);
  if (records.length !== 1) {
    fail(`expected one 'rosbag2' Metadata record, found ${records.length}`);
  } else {
    const embedded = YAML.parse(records[0].metadata.get("serialized_metadata") ?? "", { intAsBigInt: true });
    if (JSON.stringify(toPlain(embedded)) !== JSON.stringify(toPlain(info))) {
      fail("the MCAP file's rosbag2 metadata differs from metadata.yaml");
    }
  }

  // --- expectations -----------------------------------------------------------------------------------
  if (expected !== undefined) {
    const byName = new Map([...topics.values()].map((t) => [t.name, t]));
    for (const [name, want] of Object.entries(expected.topics ?? {})) {
      const topic = byName.get(name);
      if (topic === undefined) {
        fail(`expected topic ${name} is missing`);
        continue;
      }
      if (want.type !== undefined && want.type !== topic.type) fail(`${name}: type ${topic.type} != ${want.type}`);
      if (want.count !== undefined && want.count !== topic.count) fail(`${name}: ${topic.count} messages != ${want.count}`);
    }
    if (expected.topics !== undefined) {
      for (const name of byName.keys()) {
        if (!(name in expected.topics)) fail(`unexpected topic ${name}`);
      }
    }
    for (const [name, messages] of Object.entries(expected.messages ?? {})) {
      const topic = byName.get(name);
      if (topic === undefined) continue;
      const mismatches = [];
      messages.forEach((want, i) => {
        if (i >= topic.decoded.length) mismatches.push(`${name}[${i}]: missing`);
        else contains(topic.decoded[i], want, `${name}[${i}]`, mismatches);
      });
      mismatches.slice(0, 10).forEach(fail);
    }
  }
  await fileHandle.close();
  const summary = {
    ok: errors.length === 0,
    errors,
    mcap_file: mcapName,
    library: reader.header.library,
    profile: reader.header.profile,
    compression,
    chunk_count: chunkCount,
    message_count: messageCount,
    ros_distro: info.ros_distro,
    metadata_version: toPlain(info.version),
    topics: [...topics.values()].map((t) => ({ name: t.name, type: t.type, count: t.count, qos: t.qos })),
  };
  if (printValues) {
    summary.values = Object.fromEntries([...topics.values()].map((t) => [t.name, toPlain(t.decoded)]));
  }
  return summary;
}

let summary;
try {
  summary = await check();
} catch (error) {
  // A reader refusing the file (a CRC, a record out of place) ends the check with its message.
  fail(`${error.message}`);
  summary = { ok: false, errors };
}
// process.exit() could cut a long output short on a pipe: the exit code is set, the output drains.
process.stdout.write(`${JSON.stringify(summary, null, 1)}\n`);
process.exitCode = summary.ok ? 0 : 1;
