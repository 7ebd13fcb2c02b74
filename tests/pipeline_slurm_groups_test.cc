// Stage groups for Slurm (pipeline/slurm_groups.h): the --group syntax, the
// rule that groups take the pipeline's stages once each in order, and the
// scripts each group gets (its resources, its stages).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "pipeline/slurm.h"
#include "pipeline/slurm_groups.h"
#include "tests/test_util.h"

namespace doasido::pipeline {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

const std::vector<std::string> kPipeline = {"probe", "activity", "bundle", "recon", "retarget"};

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(SlurmGroups, ParsesRangesListsAndResources) {
  SlurmGroup defaults;
  defaults.partition = "cpu";
  defaults.time = "04:00:00";
  const SlurmGroup a = ParseSlurmGroup("probe..activity cpus=4", kPipeline, defaults, 1);
  EXPECT_EQ(a.name, "g1");
  EXPECT_EQ(a.stages, (std::vector<std::string>{"probe", "activity"}));
  EXPECT_EQ(a.partition, "cpu");
  EXPECT_EQ(a.cpus_per_task, 4);
  EXPECT_EQ(a.time, "04:00:00");
  const SlurmGroup b =
      ParseSlurmGroup("bundle name=gpu partition=gpu gpus=2 mem=32G", kPipeline, defaults, 2);
  EXPECT_EQ(b.name, "gpu");
  EXPECT_EQ(b.stages, (std::vector<std::string>{"bundle"}));
  EXPECT_EQ(b.partition, "gpu");
  EXPECT_EQ(b.gres, "gpu:2");
  EXPECT_EQ(b.mem, "32G");
  const SlurmGroup c = ParseSlurmGroup("recon,retarget time=01:00:00", kPipeline, defaults, 3);
  EXPECT_EQ(c.stages, (std::vector<std::string>{"recon", "retarget"}));
  EXPECT_EQ(c.time, "01:00:00");
  EXPECT_NO_THROW(CheckSlurmGroups({a, b, c}, kPipeline));
  EXPECT_EQ(GroupOfStage({a, b, c}, "recon"), 2);
  EXPECT_EQ(GroupOfStage({a, b, c}, "hands"), -1);
}

TEST(SlurmGroups, BadSpecsAndCoveragesAreRefusedByName) {
  const SlurmGroup d;
  EXPECT_THAT(Message([&] { ParseSlurmGroup("probe..trak", kPipeline, d, 1); }),
              HasSubstr("'trak' is not a stage of the pipeline"));
  EXPECT_THAT(Message([&] { ParseSlurmGroup("recon..probe", kPipeline, d, 1); }),
              HasSubstr("ends before it starts"));
  EXPECT_THAT(Message([&] { ParseSlurmGroup("bundle gpus=two", kPipeline, d, 1); }),
              HasSubstr("gpus must be a whole number"));
  EXPECT_THAT(Message([&] { ParseSlurmGroup("bundle queue=gpu", kPipeline, d, 1); }),
              HasSubstr("unknown key 'queue'"));
  EXPECT_THAT(Message([&] { ParseSlurmGroup("bundle mem=8G;rm", kPipeline, d, 1); }),
              HasSubstr("is not a Slurm value"));
  EXPECT_THAT(Message([&] { ParseSlurmGroup("", kPipeline, d, 1); }), HasSubstr("names no stages"));
  EXPECT_EQ(Message([&] { ParseSlurmGroup("bundle", kPipeline, d, 1); }), "no error");

  auto group = [&](const std::string& spec, int n) { return ParseSlurmGroup(spec, kPipeline, d, n); };
  EXPECT_THAT(Message([&] { CheckSlurmGroups({group("probe..bundle", 1), group("retarget", 2)}, kPipeline); }),
              HasSubstr("they take probe,activity,bundle,retarget; the pipeline is "
                        "probe,activity,bundle,recon,retarget"));
  EXPECT_THAT(Message([&] {
                CheckSlurmGroups({group("bundle..retarget", 1), group("probe..activity", 2)},
                                 kPipeline);
              }),
              HasSubstr("once each, in order"));
  EXPECT_THAT(Message([&] {
                CheckSlurmGroups({group("probe..bundle name=x", 1), group("recon..retarget name=x", 2)},
                                 kPipeline);
              }),
              HasSubstr("two groups are named 'x'"));
  EXPECT_THAT(Message([&] { CheckSlurmGroups({group("probe..bundle", 1)}, kPipeline); }),
              HasSubstr("field group"));
}

TEST(SlurmGroups, EachGroupScriptRunsItsStagesWithItsResources) {
  doasido::testing::TempDir dir;
  SlurmOptions o;
  o.doasido = "/opt/doasido";
  o.account = "lab";
  const SlurmGroup cpu = ParseSlurmGroup("probe..activity name=filters partition=cpu cpus=4",
                                         kPipeline, o.defaults, 1);
  const SlurmGroup gpu = ParseSlurmGroup("bundle name=gpu partition=gpu gpus=1 time=02:00:00",
                                         kPipeline, o.defaults, 2);
  const SlurmGroup rest = ParseSlurmGroup("recon..retarget", kPipeline, o.defaults, 3);
  const auto scripts = WriteSlurmScripts(dir.path(), dir / "parent.db",
                                         {dir / "a/doasido.db", dir / "b/doasido.db"},
                                         {cpu, gpu, rest}, o);
  ASSERT_EQ(scripts.groups.size(), 3u);
  EXPECT_EQ(scripts.groups[1].filename(), "group-2-gpu.sbatch");
  const std::string filters = doasido::testing::ReadFile(scripts.groups[0]);
  EXPECT_THAT(filters, HasSubstr("#SBATCH --partition=cpu\n"));
  EXPECT_THAT(filters, HasSubstr("#SBATCH --cpus-per-task=4\n"));
  EXPECT_THAT(filters, HasSubstr("#SBATCH --array=0-1\n"));
  EXPECT_THAT(filters, HasSubstr("--stages probe,activity\n"));
  EXPECT_THAT(filters, Not(HasSubstr("--gres")));
  const std::string model = doasido::testing::ReadFile(scripts.groups[1]);
  EXPECT_THAT(model, HasSubstr("#SBATCH --partition=gpu\n"));
  EXPECT_THAT(model, HasSubstr("#SBATCH --gres=gpu:1\n"));
  EXPECT_THAT(model, HasSubstr("#SBATCH --time=02:00:00\n"));
  EXPECT_THAT(model, HasSubstr("#SBATCH --account=lab\n"));
  EXPECT_THAT(model, HasSubstr("--stages bundle\n"));
  EXPECT_THAT(doasido::testing::ReadFile(scripts.groups[2]), HasSubstr("--stages recon,retarget\n"));
  EXPECT_THAT(doasido::testing::ReadFile(scripts.merge), Not(HasSubstr("--gres")));

  // One group of the whole pipeline: the script of before, without --stages.
  SlurmGroup all = o.defaults;
  const auto one = WriteSlurmScripts(dir / "one", dir / "parent.db", {dir / "a/doasido.db"}, {all}, o);
  ASSERT_EQ(one.groups.size(), 1u);
  EXPECT_EQ(one.groups[0].filename(), "array.sbatch");
  EXPECT_THAT(doasido::testing::ReadFile(one.groups[0]), Not(HasSubstr("--stages")));
}

}  // namespace
}  // namespace doasido::pipeline
