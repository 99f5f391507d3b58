// Speak to omnibot's Foxglove live server with Foxglove's own protocol client (@foxglove/ws-protocol's
// FoxgloveClient over the `ws` package, offering only "foxglove.websocket.v1", as Lichtblick does):
//   node foxglove_client.mjs '{"url": "ws://...", "origin": "https://...", "subscribe": ["/odom", "/tf"],
//                              "publish": {"topic": "/cmd_vel", "twist": {"linear": {...}, "angular": {...}}}}'
// Prints JSON lines: {"event": "open", "protocol"}, {"event": "serverInfo", "info"}, {"event": "channels",
// "channels"} (once every topic to subscribe is advertised, then it subscribes), {"event": "published",
// "encoding", "schemaName", "size"} (a client channel advertised as the Teleop panel's is, one twist
// written with Foxglove's writer in the encoding Lichtblick would pick from the server's), or
// {"event": "refused", "status", "body"} when the handshake is refused. Then it reads stdin for
// {"until": {"/odom": "NS", ...}}: once a message logged at NS or later arrived on each topic, it prints
// every message decoded with @foxglove/rosmsg2-serialization ({"event": "message", "topic", "logTime",
// "message"}) and {"event": "done", "statuses"}, and closes. Without "subscribe" it closes after the
// server's info.
import { createInterface } from "node:readline";
import { parse } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: its exports as one object
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;

const config = JSON.parse(process.argv[2]);
const wanted = config.subscribe ?? [];
// Lichtblick's choice of a client channel's encoding: the server's first among these (json if it says none)
const PUBLICATION_ENCODINGS = ["json", "ros1", "cdr"];
// the Teleop panel's schema (geometry_msgs/Twist with its Vector3), as ROS message text
const TWIST = `geometry_msgs/Vector3 linear
geometry_msgs/Vector3 angular
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
`;

const print = (record) =>
  console.log(
    JSON.stringify(record, (_key, value) => {
      if (typeof value === "bigint") return value.toString();
      if (ArrayBuffer.isView(value)) return Array.from(value);
      if (typeof value === "number" && !Number.isFinite(value)) return String(value);
      return value;
    }),
  );

const headers = config.origin ? { Origin: config.origin } : {};
const ws = new WebSocket(config.url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL], { headers });
ws.on("unexpected-response", (_request, response) => {
  let body = "";
  response.setEncoding("utf8");
  response.on("data", (chunk) => (body += chunk));
  response.on("end", () => {
    print({ event: "refused", status: response.statusCode, body });
    process.exit(0);
  });
});
const client = new FoxgloveClient({ ws });

let info;
const channels = new Map(); // topic -> channel
const subscriptions = new Map(); // subscription id -> { topic, reader }
const received = [];
const newest = new Map(); // topic -> newest log time (BigInt)
const statuses = [];
let until;
let subscribed = false;

client.on("open", () => print({ event: "open", protocol: ws.protocol }));
client.on("error", (error) => print({ event: "error", error: String(error) }));
client.on("close", (event) => {
  print({ event: "close", code: event.code });
  process.exit(0);
});
client.on("status", (status) => statuses.push(status));
client.on("serverInfo", (serverInfo) => {
  info = serverInfo;
  print({ event: "serverInfo", info });
  if (wanted.length === 0) client.close();
  else ready();
});
client.on("advertise", (advertised) => {
  for (const channel of advertised) channels.set(channel.topic, channel);
  ready();
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const sub = subscriptions.get(subscriptionId);
  if (sub === undefined) throw new Error(`message on subscription ${subscriptionId}, never made`);
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  received.push({ event: "message", topic: sub.topic, logTime: timestamp, message: sub.reader.readMessage(bytes) });
  newest.set(sub.topic, timestamp);
  finish();
});

function ready() {
  if (subscribed || info === undefined || !wanted.every((topic) => channels.has(topic))) return;
  subscribed = true;
  print({ event: "channels", channels: [...channels.values()].map(({ schema, ...rest }) => rest) });
  for (const topic of wanted) {
    const channel = channels.get(topic);
    if (channel.encoding !== "cdr" || channel.schemaEncoding !== "ros2msg") {
      throw new Error(`${topic}: ${channel.encoding} / ${channel.schemaEncoding}, expected cdr / ros2msg`);
    }
    const reader = new MessageReader(parse(channel.schema, { ros2: true }));
    subscriptions.set(client.subscribe(channel.id), { topic, reader });
  }
  if (config.publish) publish(config.publish);
}

function publish({ topic, twist }) {
  if (!(info.capabilities ?? []).includes("clientPublish")) throw new Error("no clientPublish");
  const encoding = info.supportedEncodings
    ? info.supportedEncodings.find((e) => PUBLICATION_ENCODINGS.includes(e))
    : "json";
  const schemaName = "geometry_msgs/Twist";
  let data;
  if (encoding === "cdr") data = new MessageWriter(parse(TWIST, { ros2: true })).writeMessage(twist);
  else if (encoding === "json") data = new TextEncoder().encode(JSON.stringify(twist));
  else throw new Error(`the server's encodings ${info.supportedEncodings}: none this client writes`);
  const id = client.advertise({ topic, encoding, schemaName });
  client.sendMessage(id, data);
  print({ event: "published", encoding, schemaName, channelId: id, size: data.byteLength });
}

function finish() {
  if (until === undefined) return;
  for (const [topic, ns] of Object.entries(until)) {
    if (!((newest.get(topic) ?? -1n) >= BigInt(ns))) return;
  }
  until = undefined;
  for (const record of received) print(record);
  print({ event: "done", statuses });
  client.close();
}

createInterface({ input: process.stdin }).on("line", (line) => {
  until = JSON.parse(line).until;
  finish();
});
