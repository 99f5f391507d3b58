// Read an MCAP file through its summary with Foxglove's indexed reader (McapIndexedReader: the
// footer, the summary's chunk indexes, then each chunk), as Foxglove's app opens a file, and print
//   {"topics": {topic: count}, "metadata": [names], "statistics": messageCount}
// It fails (exit 1, the error on stderr) on a file without a valid summary.
import { open } from "node:fs/promises";
import { McapIndexedReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const handle = await open(process.argv[2], "r");
const readable = {
  size: async () => BigInt((await handle.stat()).size),
  read: async (offset, size) => {
    const buffer = new Uint8Array(Number(size));
    await handle.read(buffer, 0, Number(size), Number(offset));
    return buffer;
  },
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers: await loadDecompressHandlers() });
const readers = new Map();
for (const [id, schema] of reader.schemasById) {
  readers.set(id, new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })));
}
const topics = {};
for await (const message of reader.readMessages({ validateCrcs: true })) {
  const channel = reader.channelsById.get(message.channelId);
  readers.get(channel.schemaId).readMessage(message.data); // every message decodes
  topics[channel.topic] = (topics[channel.topic] ?? 0) + 1;
}
const metadata = [];
for await (const record of reader.readMetadata()) metadata.push(record.name);
console.log(
  JSON.stringify({ topics, metadata, statistics: Number(reader.statistics?.messageCount ?? -1) }),
);
await handle.close();
