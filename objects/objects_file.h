// What `doasido objects` writes for one input (<out>/<stem>.json): the
// objects.json record of the objects stage (objects/object_bundle_writer.h
// LiftedObjectsJson: per frame and object the box keypoints, center_camera,
// rotation_camera, size_m, scale_assumed) for the tracks the models found,
// plus the input's "width", "height", "fps" and the models' "models" costs
// (objects/box_keypoints_json.h). The command has no hands in 3D, so every
// size is its category's prior (scale_assumed true) and the camera is the
// K it is given. Every track counts, however short (a still image has one
// frame); "frame" counts from "first_frame".
#pragma once

#include "core/config.h"
#include "core/geometry.h"
#include "objects/objects_config.h"
#include "objects/objects_in_video.h"

namespace doasido::objects {

Json ObjectsFileJson(const DetectedObjects& detected, const Mat3& K, const ObjectsConfig& config);

}  // namespace doasido::objects
