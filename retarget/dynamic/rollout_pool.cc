#include "retarget/dynamic/rollout_pool.h"

#include <algorithm>

namespace doasido::retarget {

RolloutPool::RolloutPool(const mjModel* m, int threads) : pool_(threads) {
  for (int i = 0; i < pool_.threads(); ++i) data_.push_back(MakeData(m));
}

}  // namespace doasido::retarget
