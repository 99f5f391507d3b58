// Read an MCAP file with Foxglove's own libraries and print every message, decoded, as JSON lines:
//   node read_mcap.mjs FILE.mcap  ->  {"topic":..., "type":..., "logTime":"ns", "message":{...}} ...
// then one line {"done": true|false, "profile": ..., "metadata": {...}} (done false: the file ends
// before its footer, e.g. a recording killed mid-run; the messages before that are still printed).
import { readFile } from "node:fs/promises";
import { McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const file = process.argv[2];
const decompressHandlers = await loadDecompressHandlers();
const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
reader.append(new Uint8Array(await readFile(file)));

const schemas = new Map();
const channels = new Map();
const metadata = {};
let profile = "";
const replacer = (_key, value) => {
  if (typeof value === "bigint") return value.toString();
  if (ArrayBuffer.isView(value)) return Array.from(value);
  if (typeof value === "number" && !Number.isFinite(value)) return String(value);
  return value;
};
for (;;) {
  let record;
  try {
    record = reader.nextRecord();
  } catch (err) {
    console.log(JSON.stringify({ error: String(err) }));
    break;
  }
  if (record === undefined) break;
  switch (record.type) {
    case "Header":
      profile = record.profile;
      break;
    case "Schema": {
      if (record.encoding !== "ros2msg") throw new Error(`schema encoding ${record.encoding}`);
      const text = new TextDecoder().decode(record.data);
      schemas.set(record.id, { name: record.name, reader: new MessageReader(parse(text, { ros2: true })) });
      break;
    }
    case "Channel":
      channels.set(record.id, record);
      break;
    case "Metadata":
      metadata[record.name] = Object.fromEntries(record.metadata);
      break;
    case "Message": {
      const channel = channels.get(record.channelId);
      const schema = schemas.get(channel.schemaId);
      if (channel.messageEncoding !== "cdr") throw new Error(`message encoding ${channel.messageEncoding}`);
      const message = schema.reader.readMessage(record.data);
      console.log(
        JSON.stringify({ topic: channel.topic, type: schema.name, logTime: record.logTime, message }, replacer),
      );
      break;
    }
    default:
      break;
  }
}
console.log(JSON.stringify({ done: reader.done(), profile, metadata }));
