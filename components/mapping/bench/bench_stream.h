#pragma once
// The mapping benchmark's measurement stream, once as messages (what the mapping component
// receives on nav/odometry, sonar/beam and sonar/scan) and once as the world-frame rays the
// library and raw OctoMap paths take, derived from those messages exactly as the component
// derives them, so that all paths must build byte-identical maps.
//
// Scene: the vehicle drives along x at 1.5 m/s (heading north, level) down a canyon with walls
// at y = +-8 m and a floor 6 m below it. A scanning sonar pings at 50 Hz, its head stepping
// 0.9 deg per ping through 360 deg with the transducer tilted 20 deg down (a cone; the tilt
// rides in each beam's mounting, SonarBeam has no tilt field); returns beyond 20 m are no-return
// beams. Each beam carries 200 intensity bins, like the simulator's. Odometry at 10 Hz (the
// simulator's navigation rate): beams between two odometry samples wait for the next one in the
// component and are placed with the interpolated pose. Multibeam swaths (swath_shape
// "canyon", the default): 256 returns fanned 2.4 rad across the canyon every 0.2 m, in the world
// frame. swath_shape "multibeam": the simulator's forward-looking multibeam
// (components/simulator/src/auv/sim/sensors/multibeam.h, its defaults): `points` beams over
// 120 deg in `rows` rows over 20 deg, pitched 25 deg down, 30 m range, at 10 Hz while the
// vehicle drives along x at 1.5 m/s, 6 m over a seabed strewn with boulders (spheres of
// 0.5-2.5 m radius); beams that meet nothing within 30 m are points at 45 m (free space only,
// as the simulator sends them); world frame.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <octomap/Pointcloud.h>

#include "auv/mapping/map_builder.h"
#include "auv/msg/all.h"

namespace auv::mapping::bench {

struct StreamOptions {
  std::size_t beams = 200000;
  std::size_t swaths = 2000;
  std::size_t points = 256;            ///< per swath (multibeam: per row)
  std::string swath_shape = "canyon";  ///< "canyon" or "multibeam" (see above)
  std::size_t rows = 4;                ///< multibeam rows per swath
  double odometry_rate = 10.0;         ///< Hz
  unsigned seed = 1;
};

/// One published message, in publication order.
struct Event {
  enum Kind { ODOMETRY, BEAM } kind;
  std::size_t index;  ///< into Stream::odometry or Stream::beams
};

struct Stream {
  // Messages. Beams and odometry are published in stamp order (`events`: an odometry sample
  // before a beam with the same stamp), clouds on their own.
  std::vector<msg::Odometry> odometry;
  std::vector<msg::SonarBeam> beams;
  std::vector<Event> events;
  std::vector<msg::PointCloud> clouds;

  // The same data for MapBuilder and raw OctoMap, one entry per message.
  std::vector<BeamGeometry> beam_geometry;             ///< sensor frame
  std::vector<Eigen::Isometry3d> beam_world_T_sensor;  ///< pose at the stamp * mounting
  /// Raw OcTree::insertPointCloud per beam: a one-point cloud from the origin to the return,
  /// or to a point past max_range (with maxrange set: free space only). Same cell updates.
  std::vector<octomap::point3d> raw_beam_origins;
  std::vector<octomap::point3d> raw_beam_ends;
  double beam_max_range = 20.0;
  std::vector<std::vector<Eigen::Vector3d>> cloud_points;
  std::vector<octomap::Pointcloud> raw_clouds;
  std::vector<Eigen::Vector3d> cloud_origins;
  double cloud_max_range = 20.0;
  std::size_t points_per_cloud = 0;

  int64_t lastBeamStampNs() const;
  int64_t lastCloudStampNs() const;
};

Stream makeStream(const StreamOptions& options);

}  // namespace auv::mapping::bench
