// Starts the Foxglove Studio app of @foxglove/studio-base 1.48.0 the way its web build does
// (deep links from the URL, remote and local MCAP files and Foxglove WebSocket connections as
// data sources), with the settings and the
// layouts kept in memory. The UMD bundle put its exports on `window`.
/* global React, ReactDOM */
"use strict";

class MemoryAppConfiguration {
  constructor(defaults) {
    this.values = new Map(Object.entries(defaults));
    this.listeners = new Map();
  }
  get(key) {
    return this.values.get(key);
  }
  async set(key, value) {
    this.values.set(key, value);
    for (const cb of this.listeners.get(key) ?? []) {
      cb(value);
    }
  }
  addChangeListener(key, cb) {
    if (!this.listeners.has(key)) {
      this.listeners.set(key, new Set());
    }
    this.listeners.get(key).add(cb);
  }
  removeChangeListener(key, cb) {
    this.listeners.get(key)?.delete(cb);
  }
}

class MemoryLayoutStorage {
  constructor() {
    this.namespaces = new Map();
  }
  ns(namespace) {
    if (!this.namespaces.has(namespace)) {
      this.namespaces.set(namespace, new Map());
    }
    return this.namespaces.get(namespace);
  }
  async list(namespace) {
    return [...this.ns(namespace).values()];
  }
  async get(namespace, id) {
    return this.ns(namespace).get(id);
  }
  async put(namespace, layout) {
    this.ns(namespace).set(layout.id, layout);
    return layout;
  }
  async delete(namespace, id) {
    this.ns(namespace).delete(id);
  }
  async importLayouts() {}
}

async function main() {
  await window.initI18n();
  const app = React.createElement(window.App, {
    deepLinks: [window.location.href],
    dataSources: [
      new window.RemoteDataSourceFactory(),
      new window.McapLocalDataSourceFactory(),
      new window.FoxgloveWebSocketDataSourceFactory(),
    ],
    appConfiguration: new MemoryAppConfiguration({
      [window.AppSetting.TELEMETRY_ENABLED]: false,
      [window.AppSetting.CRASH_REPORTING_ENABLED]: false,
      [window.AppSetting.SHOW_OPEN_DIALOG_ON_STARTUP]: false,
      [window.AppSetting.HIDE_SIGN_IN_PROMPT]: true,
    }),
    layoutStorage: new MemoryLayoutStorage(),
    extensionLoaders: [],
    enableLaunchPreferenceScreen: false,
    enableGlobalCss: true,
  });
  ReactDOM.render(app, document.getElementById("root"));
}

main().catch((err) => {
  console.error("boot failed", err);
  document.body.setAttribute("data-boot-error", String(err));
});
