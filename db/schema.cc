#include "db/schema.h"

namespace doasido::db {

const std::vector<std::string>& Migrations() {
  static const std::vector<std::string> kMigrations = {
      // 1: the first schema.
      R"sql(
CREATE TABLE pipeline (
  position INTEGER PRIMARY KEY,
  stage TEXT NOT NULL UNIQUE
);

CREATE TABLE videos (
  id INTEGER PRIMARY KEY,
  path TEXT NOT NULL UNIQUE,          -- relative to the database folder, or a URL
  width INTEGER, height INTEGER, fps REAL, frame_count INTEGER, duration_s REAL,
  variable_frame_rate INTEGER, rotation_deg INTEGER, codec TEXT,
  probed_at REAL
);

CREATE TABLE clips (
  id INTEGER PRIMARY KEY,
  video_id INTEGER NOT NULL REFERENCES videos(id),
  external_id TEXT,
  start_frame INTEGER, end_frame INTEGER,   -- inclusive, as in the source list
  start_s REAL, end_s REAL,
  source_list TEXT, source_line INTEGER,
  metadata TEXT NOT NULL DEFAULT '{}',
  created_at REAL NOT NULL
);
CREATE UNIQUE INDEX clips_span ON clips(video_id, IFNULL(start_frame, -1), IFNULL(end_frame, -1),
                                        IFNULL(start_s, -1), IFNULL(end_s, -1));
CREATE INDEX clips_external ON clips(external_id);

CREATE TABLE stage_runs (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  position INTEGER NOT NULL,
  state TEXT NOT NULL CHECK (state IN ('pending', 'running', 'done', 'failed')),
  attempts INTEGER NOT NULL DEFAULT 0,
  lease_owner TEXT, lease_expires REAL,
  param_hash TEXT,
  verdict TEXT CHECK (verdict IN ('pass', 'reject', 'flag')),
  reason TEXT,
  started_at REAL, finished_at REAL, duration_s REAL,
  error TEXT,
  UNIQUE (clip_id, stage)
);
CREATE INDEX stage_runs_open ON stage_runs(id) WHERE state IN ('pending', 'running');

CREATE TABLE measurements (
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  param_hash TEXT NOT NULL,
  data TEXT NOT NULL,                 -- JSON: raw signals and summary numbers
  created_at REAL NOT NULL,
  PRIMARY KEY (clip_id, stage)
);

CREATE TABLE verdicts (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  verdict TEXT NOT NULL CHECK (verdict IN ('pass', 'reject', 'flag')),
  reason TEXT,
  source TEXT NOT NULL,               -- 'stage', 'rethreshold' or 'human'
  param_hash TEXT,
  created_at REAL NOT NULL
);
CREATE INDEX verdicts_clip ON verdicts(clip_id, stage);

CREATE TABLE reviews (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  reviewer TEXT NOT NULL,
  decision TEXT NOT NULL CHECK (decision IN ('accept', 'reject')),
  reason TEXT,
  created_at REAL NOT NULL
);

CREATE TABLE artifacts (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  kind TEXT NOT NULL,
  path TEXT NOT NULL,                 -- relative to the database folder
  created_at REAL NOT NULL,
  UNIQUE (clip_id, stage, kind, path)
);

CREATE TABLE detections (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  frame INTEGER NOT NULL,
  kind TEXT NOT NULL CHECK (kind IN ('hand', 'object')),
  x1 REAL NOT NULL, y1 REAL NOT NULL, x2 REAL NOT NULL, y2 REAL NOT NULL,
  score REAL NOT NULL,
  contact_state INTEGER NOT NULL, hand_side INTEGER NOT NULL,
  dx REAL NOT NULL, dy REAL NOT NULL, magnitude REAL NOT NULL,
  source TEXT NOT NULL
);
CREATE INDEX detections_clip ON detections(clip_id, frame);

CREATE TABLE events (
  id INTEGER PRIMARY KEY,
  at REAL NOT NULL,
  clip_id INTEGER,
  stage TEXT,
  kind TEXT NOT NULL,                 -- 'ingest', 'claim', 'done', 'retry', 'failed', ...
  worker TEXT,
  detail TEXT
);
CREATE INDEX events_clip ON events(clip_id);
)sql",
      // 2: preference studies (review module): items compare two renderings
      // of a source clip; each trial is one rater's judgement of one item,
      // with the randomised left/right layout it was shown in.
      R"sql(
CREATE TABLE studies (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  raters_per_item INTEGER NOT NULL CHECK (raters_per_item >= 1),
  seed INTEGER NOT NULL,               -- left/right layout seed
  items_file TEXT,
  created_at REAL NOT NULL
);

CREATE TABLE study_items (
  id INTEGER PRIMARY KEY,
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  position INTEGER NOT NULL,
  item_id TEXT NOT NULL,
  source_video TEXT NOT NULL,          -- relative to the database folder when inside it
  a_video TEXT NOT NULL,
  b_video TEXT NOT NULL,
  a_label TEXT NOT NULL,
  b_label TEXT NOT NULL,
  UNIQUE (study_id, item_id)
);

CREATE TABLE study_trials (
  id INTEGER PRIMARY KEY,
  item_id INTEGER NOT NULL REFERENCES study_items(id) ON DELETE CASCADE,
  rater TEXT NOT NULL,
  left_is_a INTEGER NOT NULL CHECK (left_is_a IN (0, 1)),
  side TEXT CHECK (side IN ('left', 'right', 'tie')),
  choice TEXT CHECK (choice IN ('a', 'b', 'tie')),
  shown_at REAL NOT NULL,
  answered_at REAL,
  UNIQUE (item_id, rater)
);
CREATE INDEX study_trials_item ON study_trials(item_id);
)sql",
      // 3: the kinematic retargeting stage is named `retarget_kinematic`
      // (its config section and artifact folder), no longer `retarget-kinematic`.
      // Artifact paths keep the folder the files were written to.
      R"sql(
UPDATE pipeline SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE stage_runs SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE measurements SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE verdicts SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE reviews SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE artifacts SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
UPDATE events SET stage = 'retarget_kinematic' WHERE stage = 'retarget-kinematic';
)sql",
      // 4: videos named by URL are downloaded into <db folder>/media by the
      // download stage; the row keeps the URL (path) and gains the local
      // file, its size and SHA-256.
      R"sql(
ALTER TABLE videos ADD COLUMN local_path TEXT;    -- relative to the database folder
ALTER TABLE videos ADD COLUMN size_bytes INTEGER;
ALTER TABLE videos ADD COLUMN sha256 TEXT;
ALTER TABLE videos ADD COLUMN downloaded_at REAL;
)sql",
      // 5: shards. Every database gets an identity (meta.uuid). A parent
      // records the shard databases it split its queue into and which clip
      // went where; a shard records its parent and the config it runs with.
      R"sql(
CREATE TABLE meta (
  key TEXT PRIMARY KEY,
  value TEXT NOT NULL
);
INSERT INTO meta VALUES ('uuid', lower(hex(randomblob(16))));

CREATE TABLE shards (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,           -- shard-000
  path TEXT NOT NULL,                  -- the shard database, stored like a video path
  config_hash TEXT NOT NULL,           -- ParamHash of the config the shard runs with
  clips INTEGER NOT NULL,
  frames INTEGER NOT NULL,
  created_at REAL NOT NULL,
  merged_at REAL,                      -- last merge
  merged_event INTEGER NOT NULL DEFAULT 0,  -- highest shard event id folded in
  slurm_job TEXT,                      -- array job id, when submitted to Slurm
  slurm_task INTEGER                   -- its task index
);

CREATE TABLE shard_clips (
  clip_id INTEGER PRIMARY KEY REFERENCES clips(id) ON DELETE CASCADE,
  shard_id INTEGER NOT NULL REFERENCES shards(id)
);
CREATE INDEX shard_clips_shard ON shard_clips(shard_id);
)sql",
      // 6: a flag at a stage whose next stage also judges stored
      // measurements (inside the filters) lets the clip go on to it.
      R"sql(
ALTER TABLE pipeline ADD COLUMN flag_continues INTEGER NOT NULL DEFAULT 0;
)sql",
      // 7: stage run dependencies. A finished run records the upstream runs
      // it consumed (JSON: stage, parameter hash, finish time,
      // artifacts); a run queued again because an upstream run changed names
      // that stage. A run that is not done carries no verdict.
      R"sql(
ALTER TABLE stage_runs ADD COLUMN inputs TEXT;
ALTER TABLE stage_runs ADD COLUMN requeued_by TEXT;
UPDATE stage_runs SET verdict = NULL, reason = NULL WHERE state != 'done';
)sql",
      // 8: artifact paths are relative to the database's artifact root
      // (meta 'artifact_root', "artifacts" for databases made before it);
      // a person's decision records the SHA-256 of the trajectory file and
      // the parameter hash it was shown, so it binds to that trajectory only.
      R"sql(
UPDATE artifacts SET path = substr(path, 11) WHERE path LIKE 'artifacts/%';
INSERT OR IGNORE INTO meta (key, value)
  SELECT 'artifact_root', 'artifacts' WHERE EXISTS (SELECT 1 FROM artifacts);
ALTER TABLE reviews ADD COLUMN artifact_sha256 TEXT;
ALTER TABLE reviews ADD COLUMN param_hash TEXT;
)sql",
      // 9: a run whose measurement did not run for the clip (an earlier
      // verdict in the order the evidence is taken removed it) records
      // verdict 'not_measured', its reason naming that verdict's stage
      // (core/records.h). SQLite cannot change a CHECK constraint: both
      // tables are rebuilt with their rows.
      R"sql(
CREATE TABLE stage_runs_v9 (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  position INTEGER NOT NULL,
  state TEXT NOT NULL CHECK (state IN ('pending', 'running', 'done', 'failed')),
  attempts INTEGER NOT NULL DEFAULT 0,
  lease_owner TEXT, lease_expires REAL,
  param_hash TEXT,
  verdict TEXT CHECK (verdict IN ('pass', 'reject', 'flag', 'not_measured')),
  reason TEXT,
  started_at REAL, finished_at REAL, duration_s REAL,
  error TEXT,
  inputs TEXT,
  requeued_by TEXT,
  UNIQUE (clip_id, stage)
);
INSERT INTO stage_runs_v9 (id, clip_id, stage, position, state, attempts, lease_owner,
  lease_expires, param_hash, verdict, reason, started_at, finished_at, duration_s, error, inputs,
  requeued_by)
  SELECT id, clip_id, stage, position, state, attempts, lease_owner, lease_expires, param_hash,
  verdict, reason, started_at, finished_at, duration_s, error, inputs, requeued_by FROM stage_runs;
DROP TABLE stage_runs;
ALTER TABLE stage_runs_v9 RENAME TO stage_runs;
CREATE INDEX stage_runs_open ON stage_runs(id) WHERE state IN ('pending', 'running');

CREATE TABLE verdicts_v9 (
  id INTEGER PRIMARY KEY,
  clip_id INTEGER NOT NULL REFERENCES clips(id) ON DELETE CASCADE,
  stage TEXT NOT NULL,
  verdict TEXT NOT NULL CHECK (verdict IN ('pass', 'reject', 'flag', 'not_measured')),
  reason TEXT,
  source TEXT NOT NULL,
  param_hash TEXT,
  created_at REAL NOT NULL
);
INSERT INTO verdicts_v9 (id, clip_id, stage, verdict, reason, source, param_hash, created_at)
  SELECT id, clip_id, stage, verdict, reason, source, param_hash, created_at FROM verdicts;
DROP TABLE verdicts;
ALTER TABLE verdicts_v9 RENAME TO verdicts;
CREATE INDEX verdicts_clip ON verdicts(clip_id, stage);
)sql",
  };
  return kMigrations;
}

}  // namespace doasido::db
