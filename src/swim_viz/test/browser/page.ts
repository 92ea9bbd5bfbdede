// The browser test's page: connects to a Foxglove WebSocket protocol server (foxglove.sdk.v1, or its older name
// foxglove.websocket.v1) with the protocol's published client (@foxglove/ws-protocol), subscribes to one topic,
// decodes each message's CDR with the channel's ros2msg schema (@foxglove/rosmsg,
// @foxglove/rosmsg2-serialization) and shows the latest one for the test to read:
//   <pre id="latest">  JSON {"topic", "field", "sec", "nanosec", "value", "count"}: the latest message's
//                      header.stamp (null without a header), the value at `field`, and how many were decoded;
//                      empty until the first message
//   <pre id="status">  what the page is doing, or "error: ..." (connection, channel or decoding errors)
// Query string: url=ws://HOST:PORT (required), topic=/name (required), field=a.b.c (optional: the value shown;
// by default the message's first float64 field that is not an array).
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { FoxgloveClient } from "@foxglove/ws-protocol";
import type { Channel } from "@foxglove/ws-protocol";
import type { MessageDefinition } from "@foxglove/message-definition";

// the WebSocket subprotocols offered, the server picks one: foxglove-sdk's servers (foxglove_bridge 3, our
// foxglove_node) accept only the protocol's new name foxglove.sdk.v1, older servers only foxglove.websocket.v1
// (FoxgloveClient.SUPPORTED_SUBPROTOCOL); the messages are the same under both names
const SUBPROTOCOLS = ["foxglove.sdk.v1", FoxgloveClient.SUPPORTED_SUBPROTOCOL];
// what the server must send on the topic: raw ROS 2 CDR described by a ROS 2 .msg schema
const MESSAGE_ENCODING = "cdr";
const SCHEMA_ENCODING = "ros2msg";

const latestElement = document.getElementById("latest") as HTMLElement;
const statusElement = document.getElementById("status") as HTMLElement;

function setStatus(text: string): void {
  statusElement.textContent = text;
}

function fail(text: string): void {
  setStatus(`error: ${text}`);
}

// the dotted path's value in a decoded message, undefined where a step is missing
function valueAt(message: unknown, path: string): unknown {
  let value: unknown = message;
  for (const step of path.split(".")) {
    if (value === null || typeof value !== "object") {
      return undefined;
    }
    value = (value as Record<string, unknown>)[step];
  }
  return value;
}

// the root type's first float64 field that is not an array: the value shown when no field is asked for
function firstScalarFloat64(definitions: MessageDefinition[]): string | undefined {
  const root = definitions[0];
  return root?.definitions.find(
    (field) => field.type === "float64" && field.isArray !== true && field.isConstant !== true,
  )?.name;
}

// JSON that holds what the decoder gives: 64-bit integers (bigint) as decimal strings
function toJson(value: unknown): string {
  return JSON.stringify(value, (_key, item) => (typeof item === "bigint" ? item.toString() : item));
}

function main(): void {
  const query = new URLSearchParams(window.location.search);
  const url = query.get("url");
  const topic = query.get("topic");
  const requestedField = query.get("field") ?? undefined;
  if (url == null || topic == null) {
    fail("the page needs ?url=ws://HOST:PORT&topic=/name");
    return;
  }

  setStatus(`connecting to ${url}`);
  const socket = new WebSocket(url, SUBPROTOCOLS);
  const client = new FoxgloveClient({ ws: socket });
  let subscriptionId: number | undefined;
  let reader: MessageReader | undefined;
  let field: string | undefined;
  let count = 0;

  client.on("open", () => setStatus(`connected to ${url} (${socket.protocol}), waiting for ${topic}`));
  client.on("error", (error) => fail(`connection: ${String(error)}`));
  client.on("close", (event) => fail(`connection closed (code ${event.code}) ${event.reason}`));
  client.on("advertise", (channels: Channel[]) => {
    const channel = channels.find((candidate) => candidate.topic === topic);
    if (channel == null || subscriptionId != null) {
      return;
    }
    if (channel.encoding !== MESSAGE_ENCODING || channel.schemaEncoding !== SCHEMA_ENCODING) {
      fail(`${topic} is ${channel.encoding}/${channel.schemaEncoding ?? "no schema encoding"}, ` +
        `not ${MESSAGE_ENCODING}/${SCHEMA_ENCODING}`);
      return;
    }
    try {
      const definitions = parse(channel.schema, { ros2: true });
      reader = new MessageReader(definitions);
      field = requestedField ?? firstScalarFloat64(definitions);
    } catch (error) {
      fail(`${topic}'s schema ${channel.schemaName}: ${String(error)}`);
      return;
    }
    subscriptionId = client.subscribe(channel.id);
    setStatus(`subscribed to ${topic} (${channel.schemaName}, channel ${channel.id}, ${socket.protocol})`);
  });
  client.on("message", ({ subscriptionId: from, data }) => {
    if (from !== subscriptionId || reader == null) {
      return;
    }
    let message: unknown;
    try {
      message = reader.readMessage(data);
    } catch (error) {
      fail(`decoding message ${count + 1} of ${topic}: ${String(error)}`);
      return;
    }
    count += 1;
    const stamp = valueAt(message, "header.stamp") as { sec: number; nanosec: number } | undefined;
    latestElement.textContent = toJson({
      topic,
      field: field ?? null,
      sec: stamp?.sec ?? null,
      nanosec: stamp?.nanosec ?? null,
      value: field == null ? null : valueAt(message, field) ?? null,
      count,
    });
  });
}

main();
