#pragma once
/// \file
/// MoveIt PlanningScene / MotionPlanRequest YAML -> chasles.v1 messages (owned by the importer).
