"""The standard gRPC health service messages (grpc.health.v1), built from a descriptor.

Debian ships no python3-grpc-health-checking, so the two messages of grpc/health/v1/health.proto
are declared here in a private descriptor pool (it does not touch the default pool).
"""

from __future__ import annotations

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

_file = descriptor_pb2.FileDescriptorProto(name="chasles_client/grpc_health_v1.proto",
                                           package="grpc.health.v1", syntax="proto3")
_request = _file.message_type.add(name="HealthCheckRequest")
_request.field.add(name="service", number=1, type=descriptor_pb2.FieldDescriptorProto.TYPE_STRING,
                   label=descriptor_pb2.FieldDescriptorProto.LABEL_OPTIONAL)
_response = _file.message_type.add(name="HealthCheckResponse")
_status = _response.enum_type.add(name="ServingStatus")
for _number, _name in enumerate(("UNKNOWN", "SERVING", "NOT_SERVING", "SERVICE_UNKNOWN")):
    _status.value.add(name=_name, number=_number)
_response.field.add(name="status", number=1, type=descriptor_pb2.FieldDescriptorProto.TYPE_ENUM,
                    type_name=".grpc.health.v1.HealthCheckResponse.ServingStatus",
                    label=descriptor_pb2.FieldDescriptorProto.LABEL_OPTIONAL)

_pool = descriptor_pool.DescriptorPool()
_pool.Add(_file)


def _message_class(name: str):  # noqa: ANN202 - a generated message class
    descriptor = _pool.FindMessageTypeByName(name)
    if hasattr(message_factory, "GetMessageClass"):  # protobuf >= 4.22
        return message_factory.GetMessageClass(descriptor)
    return message_factory.MessageFactory(_pool).GetPrototype(descriptor)


HealthCheckRequest = _message_class("grpc.health.v1.HealthCheckRequest")
HealthCheckResponse = _message_class("grpc.health.v1.HealthCheckResponse")

#: Full method name of the health check.
CHECK_METHOD = "/grpc.health.v1.Health/Check"


def status_name(response: "HealthCheckResponse") -> str:  # type: ignore[valid-type]
    """``"SERVING"``, ``"NOT_SERVING"``, ``"SERVICE_UNKNOWN"`` or ``"UNKNOWN"``."""
    return HealthCheckResponse.DESCRIPTOR.enum_types_by_name["ServingStatus"].values_by_number[
        response.status].name
