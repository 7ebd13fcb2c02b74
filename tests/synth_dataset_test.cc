// The dataset as files: same seed gives byte-identical ground truth, the
// bundle reads back equal through recon::ReadBundle, the clip list and VOC
// folder have the documented layout, and the defect mix is honoured.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <opencv2/videoio.hpp>
#include <regex>
#include <sstream>

#include "recon/bundle/bundle.h"
#include "synth/generator.h"
#include "tests/test_util.h"

namespace doasido::synth {
namespace {

namespace fs = std::filesystem;

std::uint64_t Fnv(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

// Relative path -> content hash of every file under `root` except videos
// (video encoders may embed timing-independent but library-version data;
// the ground truth is what must be identical).
std::map<std::string, std::uint64_t> HashTree(const fs::path& root) {
  std::map<std::string, std::uint64_t> out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), root).string();
    if (rel.rfind("videos/", 0) == 0) continue;
    out[rel] = Fnv(testing::ReadFile(e.path()));
  }
  return out;
}

SynthConfig SmallConfig() {
  SynthConfig cfg;
  cfg.width = 160;
  cfg.height = 120;
  cfg.frames = 24;
  cfg.clips = 3;
  cfg.seed = 5;
  cfg.track_points = 16;
  cfg.mix = "clean=1,cut=1,static=1";
  return cfg;
}

TEST(Dataset, SameSeedSameGroundTruthBytes) {
  testing::TempDir a, b, c;
  SynthConfig cfg = SmallConfig();
  GenerateDataset(cfg, a.path());
  GenerateDataset(cfg, b.path());
  const auto ha = HashTree(a.path()), hb = HashTree(b.path());
  EXPECT_GT(ha.size(), 100u);  // bundles (depth, masks per frame), XML, gt, csv
  EXPECT_EQ(ha, hb);
  cfg.seed = 6;
  GenerateDataset(cfg, c.path());
  EXPECT_NE(HashTree(c.path()), ha);
}

void ExpectMatEq(const cv::Mat& a, const cv::Mat& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  ASSERT_EQ(a.type(), b.type()) << what;
  cv::Mat diff;
  cv::compare(a, b, diff, cv::CMP_NE);
  // inf == inf compares equal; NaN is never written.
  EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << what;
}

void ExpectPoseEq(const Pose& a, const Pose& b) {
  EXPECT_EQ(a.q.coeffs(), b.q.coeffs());
  EXPECT_EQ(a.t, b.t);
}

TEST(Dataset, BundleRoundTripsThroughTheReader) {
  SynthConfig cfg = SmallConfig();
  cfg.two_hand_fraction = 1.0;
  cfg.point_maps = true;
  const RenderedClip clip = RenderClip(cfg, 1, DefectKind::kZoom);  // per-frame K
  testing::TempDir dir;
  recon::WriteBundle(clip.bundle, dir.path());
  const recon::ClipBundle r = recon::ReadBundle(dir.path());
  const recon::ClipBundle& w = clip.bundle;
  EXPECT_EQ(r.width, w.width);
  EXPECT_EQ(r.height, w.height);
  EXPECT_EQ(r.frames, w.frames);
  EXPECT_EQ(r.fps, w.fps);
  EXPECT_EQ(r.producers, w.producers);
  ASSERT_EQ(r.K.size(), w.K.size());
  EXPECT_EQ(w.K.size(), static_cast<size_t>(cfg.frames));
  for (size_t t = 0; t < w.K.size(); ++t) EXPECT_EQ(r.K[t], w.K[t]);
  ASSERT_EQ(r.depth.size(), w.depth.size());
  for (int t = 0; t < w.frames; ++t) {
    ExpectMatEq(r.depth[t], w.depth[t], "depth");
    ASSERT_EQ(r.points.size(), w.points.size());
    // Point maps: NaN where depth is invalid, so compare the finite parts.
    for (int y = 0; y < w.height; y += 7) {
      for (int x = 0; x < w.width; x += 7) {
        const cv::Vec3f a = r.points[t].at<cv::Vec3f>(y, x), c = w.points[t].at<cv::Vec3f>(y, x);
        if (std::isfinite(c[2])) {
          EXPECT_EQ(a, c);
          EXPECT_EQ(c[2], w.depth[t].at<float>(y, x));
        }
      }
    }
    ExpectMatEq(r.mask_object[t], w.mask_object[t], "mask_object");
    ExpectMatEq(r.mask_hand_left[t], w.mask_hand_left[t], "mask_hand_left");
    ExpectMatEq(r.mask_hand_right[t], w.mask_hand_right[t], "mask_hand_right");
    ExpectPoseEq(r.object_poses[t], w.object_poses[t]);
    EXPECT_EQ(r.gravity_up[t], w.gravity_up[t]);
    ASSERT_EQ(r.candidates[t].size(), w.candidates[t].size());
    for (size_t n = 0; n < w.candidates[t].size(); ++n) {
      ExpectPoseEq(r.candidates[t][n].pose, w.candidates[t][n].pose);
      EXPECT_EQ(r.candidates[t][n].scale, w.candidates[t][n].scale);
    }
  }
  for (auto member : {&recon::ClipBundle::hand_left, &recon::ClipBundle::hand_right}) {
    ASSERT_TRUE((w.*member).has_value());
    ASSERT_TRUE((r.*member).has_value());
    const recon::HandTrack &hw = *(w.*member), &hr = *(r.*member);
    EXPECT_EQ(hr.valid, hw.valid);
    EXPECT_EQ(hr.faces, hw.faces);
    ASSERT_EQ(hr.joints.size(), hw.joints.size());
    ASSERT_EQ(hr.verts.size(), hw.verts.size());
    for (size_t t = 0; t < hw.joints.size(); ++t) {
      EXPECT_EQ(hr.joints[t], hw.joints[t]);
      EXPECT_EQ(hr.verts[t], hw.verts[t]);
    }
  }
  ASSERT_TRUE(r.object_mesh.has_value());
  EXPECT_EQ(r.object_mesh->faces, w.object_mesh->faces);
  EXPECT_EQ(r.object_mesh->vertices, w.object_mesh->vertices);
  ASSERT_TRUE(r.tracks.has_value());
  EXPECT_EQ(r.tracks->x, w.tracks->x);
  EXPECT_EQ(r.tracks->y, w.tracks->y);
  EXPECT_EQ(r.tracks->visible, w.tracks->visible);
  EXPECT_EQ(r.tracks->query, w.tracks->query);
}

TEST(Dataset, TracksFollowTheObjectAndRespectOcclusion) {
  SynthConfig cfg = SmallConfig();
  cfg.width = 320;
  cfg.height = 240;
  cfg.track_points = 64;
  const RenderedClip clip = RenderClip(cfg, 0, DefectKind::kClean);
  const recon::ClipBundle& b = clip.bundle;
  int visible = 0, hidden = 0;
  for (int i = 0; i < cfg.track_points; ++i) {
    for (int t = 0; t < cfg.frames; ++t) {
      const int x = static_cast<int>(std::lround(b.tracks->x(i, t)));
      const int y = static_cast<int>(std::lround(b.tracks->y(i, t)));
      if (b.tracks->visible(i, t)) {
        ++visible;
        ASSERT_TRUE(x >= 0 && y >= 0 && x < cfg.width && y < cfg.height);
        EXPECT_EQ(b.mask_object[t].at<std::uint8_t>(y, x), 255);
      } else {
        ++hidden;  // back side, or behind a hand
      }
    }
  }
  EXPECT_GT(visible, cfg.track_points * cfg.frames / 5);
  EXPECT_GT(hidden, cfg.track_points * cfg.frames / 5);
}

TEST(Dataset, FilesFollowTheDocumentedLayout) {
  testing::TempDir dir;
  SynthConfig cfg = SmallConfig();
  const DatasetSummary s = GenerateDataset(cfg, dir.path());
  EXPECT_EQ(s.clips, 3);
  EXPECT_EQ(s.defect_counts.at("clean"), 1);
  EXPECT_EQ(s.defect_counts.at("cut"), 1);
  EXPECT_EQ(s.defect_counts.at("static"), 1);
  // clips.csv
  std::istringstream csv(testing::ReadFile(dir / "clips.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("video,id,start_frame,end_frame,source,defects", 0), 0u);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::vector<std::string> cols;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cols.push_back(c);
    ASSERT_GE(cols.size(), 6u);
    const fs::path video = dir.path() / cols[0];
    ASSERT_TRUE(fs::exists(video)) << video;
    EXPECT_EQ(video.stem().string(), cols[1]);
    EXPECT_EQ(cols[2], "0");
    EXPECT_EQ(cols[3], std::to_string(cfg.frames - 1));
    cv::VideoCapture cap(video.string(), cv::CAP_FFMPEG);
    int n = 0;
    for (cv::Mat f; cap.read(f);) {
      EXPECT_EQ(f.cols, cfg.width);
      ++n;
    }
    EXPECT_EQ(n, cfg.frames);
    // One VOC file per frame, named for the video stem and 0-based frame.
    for (int t : {0, cfg.frames - 1}) {
      char name[128];
      std::snprintf(name, sizeof name, "synth_v_%s_frame%06d.xml", cols[1].c_str(), t);
      EXPECT_TRUE(fs::exists(dir.path() / "Annotations" / name)) << name;
    }
    EXPECT_TRUE(fs::exists(dir.path() / "gt" / (cols[1] + ".json")));
    EXPECT_TRUE(fs::exists(dir.path() / "bundles" / cols[1] / "meta.json"));
  }
  EXPECT_EQ(rows, 3);
  int xml = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "Annotations"))
    xml += e.path().extension() == ".xml";
  EXPECT_EQ(xml, 3 * cfg.frames);
}

TEST(Dataset, VocCarriesContactStatesOfTheEpisode) {
  SynthConfig cfg = SmallConfig();
  cfg.width = 320;
  cfg.height = 240;
  cfg.frames = 40;
  const RenderedClip clip = RenderClip(cfg, 0, DefectKind::kClean);
  int contact_frames = 0;
  for (int t = 0; t < cfg.frames; ++t) {
    const Json& f = clip.gt["per_frame"][t];
    const bool contact = f["contact"][0].get<bool>() || f["contact"][1].get<bool>();
    const std::string xml = VocXml(clip.voc[t]);
    const bool in_contact_xml = xml.find("<contactstate>3</contactstate>") != std::string::npos;
    const bool hand_visible = f["hand_pixels"][0].get<int>() + f["hand_pixels"][1].get<int>() > 0;
    if (hand_visible) {
      EXPECT_EQ(in_contact_xml, contact) << "frame " << t;
    }
    if (contact && hand_visible) {
      ++contact_frames;
      // The touching hand names the object's box.
      EXPECT_TRUE(std::regex_search(xml, std::regex("<contactstate>3</contactstate>\\s*"
                                                    "<handside>[01]</handside>\\s*"
                                                    "<objxmin>[0-9]+</objxmin>")));
      EXPECT_NE(xml.find("<name>targetobject</name>"), std::string::npos);
      std::smatch m;
      ASSERT_TRUE(std::regex_search(xml, m, std::regex("<magnitude>([0-9.]+)</magnitude>")));
      EXPECT_GT(std::stod(m[1]), 0.0);
    }
  }
  EXPECT_GT(contact_frames, cfg.frames / 4);
}

TEST(Mix, ParsesAndAssignsEveryKindAskedFor) {
  const auto mix =
      ParseMix("clean=0.4, cut=0.1,fade=0.1,pan=0.1,out_of_frame=0.1,no_contact=0.1,static=0.1");
  EXPECT_EQ(mix.size(), 7u);
  EXPECT_NEAR(mix.at(DefectKind::kClean), 0.4, 1e-12);
  const auto kinds = AssignDefects(mix, 20, 3);
  ASSERT_EQ(kinds.size(), 20u);
  std::map<DefectKind, int> n;
  for (auto k : kinds) n[k]++;
  EXPECT_EQ(n[DefectKind::kClean], 8);
  for (auto k : {DefectKind::kCut, DefectKind::kCrossFade, DefectKind::kPan, DefectKind::kHandOut,
                 DefectKind::kNoContact, DefectKind::kStatic}) {
    EXPECT_EQ(n[k], 2);
  }
  // Few clips: every kind still appears once.
  const auto few = AssignDefects(mix, 7, 3);
  std::map<DefectKind, int> m;
  for (auto k : few) m[k]++;
  EXPECT_EQ(m.size(), 7u);
  EXPECT_EQ(AssignDefects(mix, 20, 3), kinds);
  EXPECT_THROW(ParseMix("clean=1,bogus=2"), Error);
  EXPECT_THROW(ParseMix("clean=x"), Error);
  EXPECT_THROW(ParseMix("clean=0"), Error);
}

}  // namespace
}  // namespace doasido::synth
